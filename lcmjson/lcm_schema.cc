/// JSON Schema of an LCM struct's JSON messages (lcm_json.cc writes them).

#include <cctype>
#include <string>

#include <nlohmann/json.hpp>

#include "lcmjson/lcm_json.h"

namespace nimble::lcmjson {

namespace {

using Json = nlohmann::ordered_json;

Json element_schema(const std::string& type) {
  if (type == "double" || type == "float") {
    return Json{{"type", Json::array({"number", "null"})}};
  }
  if (type == "boolean") return Json{{"type", "boolean"}};
  if (type == "string") return Json{{"type", "string"}};
  Json s{{"type", "integer"}};
  if (type == "byte") {
    s["minimum"] = 0;
    s["maximum"] = 255;
  } else if (type == "int8_t") {
    s["minimum"] = -128;
    s["maximum"] = 127;
  } else if (type == "int16_t") {
    s["minimum"] = -32768;
    s["maximum"] = 32767;
  } else if (type == "int32_t") {
    s["minimum"] = -2147483648LL;
    s["maximum"] = 2147483647LL;
  }
  return s;
}

}  // namespace

int typical_encoded_size(const LcmStruct& type) {
  int bytes = 8;  // the fingerprint
  for (const LcmField& f : type.fields) {
    int one = 0;
    if (f.type == "string")
      one = 4 + kTypicalStringBytes + 1;  // length, text, NUL
    else if (f.type == "int8_t" || f.type == "byte" || f.type == "boolean")
      one = 1;
    else if (f.type == "int16_t")
      one = 2;
    else if (f.type == "int32_t" || f.type == "float")
      one = 4;
    else
      one = 8;  // int64_t, double
    int count = 1;
    for (const std::string& d : f.dims) {
      count *= !d.empty() && std::isdigit(static_cast<unsigned char>(d[0])) ? std::stoi(d) : kTypicalArrayLength;
    }
    bytes += one * count;
  }
  return bytes;
}

std::string json_schema(const LcmStruct& type) {
  Json properties = Json::object();
  Json required = Json::array();
  for (const auto& f : type.fields) {
    Json s = element_schema(f.type);
    std::string description = f.comment;
    if (f.type == "double" || f.type == "float") {
      description += description.empty() ? "" : " ";
      description += "(null where the value is NaN or infinite.)";
    }
    // Arrays are flat: a fixed size gives min and max items; a variable one names its count field.
    for (auto d = f.dims.rbegin(); d != f.dims.rend(); ++d) {
      Json array{{"type", "array"}, {"items", s}};
      if ((*d)[0] >= '0' && (*d)[0] <= '9') {
        array["minItems"] = std::stoll(*d);
        array["maxItems"] = std::stoll(*d);
      } else {
        description += (description.empty() ? "" : " ") + std::string("(Length: the field ") + *d + ".)";
      }
      s = array;
    }
    if (!description.empty()) s["description"] = description;
    if (!f.unit.empty()) s["x-unit"] = f.unit;
    properties[f.name] = s;
    required.push_back(f.name);
  }
  Json schema{{"$schema", "http://json-schema.org/draft-07/schema#"}, {"title", type.full_name()}, {"type", "object"}};
  if (!type.comment.empty()) schema["description"] = type.comment;
  schema["properties"] = properties;
  schema["required"] = required;
  schema["additionalProperties"] = false;
  if (!type.consts.empty()) {
    Json consts = Json::object();
    for (const auto& c : type.consts) {
      Json v = Json::parse(c.value, nullptr, false);
      consts[c.name] = Json{{"value", v.is_discarded() ? Json(c.value) : v}, {"description", c.comment}};
    }
    schema["x-constants"] = consts;
  }
  return schema.dump();
}

}  // namespace nimble::lcmjson
