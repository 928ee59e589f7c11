/// rig_message_list_gen: the rig's one list of message types, written at build time from the
/// .lcm files (lcmtypes/), as a C++ header.
///
///   rig_message_list_gen <output header> <file.lcm>...
///
/// The files are parsed with lcmjson's parser (lcmjson/lcm_parse.cc, the one that also gives the
/// viewers their types), and the header holds, for every type in the order of the files given:
/// the X-macro NIMBLE_RIG_MESSAGES(X), the comma list NIMBLE_RIG_MESSAGE_TYPES, and the
/// specialisation nimble::MessageFields<type> with each field's name, LCM type and size, a visitor
/// that calls f("name", m.name) for every field in .lcm order, and a binder that calls
/// f("name", v.name, m.name) for a value struct with the message's field names. Everything that
/// needs every type or every field (the conversions of contract/messages.h, the fault values of
/// contract/faults.h, the fuzz targets, the bus flood, the run monitor, the tests' samples) goes
/// through it, so a type is added by adding its .lcm file (docs/contract.md).
///
/// The header is C++11, as the generated types are: it is installed with them.

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "lcmjson/lcm_json.h"

namespace {

using nimble::lcmjson::LcmField;
using nimble::lcmjson::LcmStruct;

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// "3", "num_channels", "2][3" (a field of more than one dimension); "" for a scalar.
std::string size_of(const LcmField& f) {
  std::string out;
  for (const auto& d : f.dims) out += (out.empty() ? "" : "][") + d;
  return out;
}

/// The specialisation of MessageFields for one type.
void write_type(std::ostream& out, const LcmStruct& s) {
  out << "/// " << s.name << " (" << s.file << "): " << s.fields.size() << " fields.\n"
      << "template <>\n"
      << "struct MessageFields<" << s.name << "> {\n"
      << "  static constexpr int field_count = " << s.fields.size() << ";\n"
      << "  static const MessageFieldInfo* fields() {\n"
      << "    static const MessageFieldInfo f[] = {\n";
  for (const auto& f : s.fields) {
    out << "        {\"" << f.name << "\", \"" << f.type << "\", \"" << size_of(f) << "\"},\n";
  }
  out << "    };\n"
      << "    return f;\n"
      << "  }\n"
      << "  template <class M, class F>\n"
      << "  static void visit(M& m, F& f) {\n";
  for (const auto& f : s.fields) out << "    f(\"" << f.name << "\", m." << f.name << ");\n";
  out << "  }\n"
      << "  template <class V, class M, class F>\n"
      << "  static void bind(V& v, M& m, F& f) {\n";
  for (const auto& f : s.fields) out << "    f(\"" << f.name << "\", v." << f.name << ", m." << f.name << ");\n";
  out << "  }\n"
      << "};\n\n";
}

/// What does not depend on the types: the field description and the generic entry points.
const char* const kPrologue = R"(
namespace nimble {

/// One field of a message as its .lcm file declares it.
struct MessageFieldInfo {
  const char* name;
  const char* type;  ///< the LCM type: int8_t, int16_t, int32_t, int64_t, byte, boolean, float, double, string
  const char* size;  ///< "" for a scalar, else the array's size: a number (fixed) or the integer field holding it
};

/// The fields of message type M (specialised below for every type): field_count, fields() (each
/// field's MessageFieldInfo, in .lcm order), visit(m, f) and bind(v, m, f).
template <class M>
struct MessageFields;

/// A message type as a value: what for_each_message_type() and with_message_type() pass.
template <class M>
struct MessageType {
  typedef M type;
};

)";

const char* const kEpilogue =
    R"(/// Calls f("name", m.name) for every field of message `m`, in .lcm order (m may be const).
template <class M, class F>
void for_each_field(M& m, F&& f) {
  MessageFields<typename std::remove_const<M>::type>::visit(m, f);
}

/// Calls f("name", v.name, m.name) for every field of message `m`, in .lcm order: `v` is any
/// struct with the message's field names (another message, or a value that carries every field);
/// a field the struct lacks does not compile, naming the field.
template <class V, class M, class F>
void bind_fields(V& v, M& m, F&& f) {
  MessageFields<typename std::remove_const<M>::type>::bind(v, m, f);
}

/// Calls f(MessageType<M>()) for every message type, in the order of NIMBLE_RIG_MESSAGES.
template <class F>
void for_each_message_type(F&& f) {
#define NIMBLE_RIG_MESSAGE_VISIT_(T) f(MessageType<T>());
  NIMBLE_RIG_MESSAGES(NIMBLE_RIG_MESSAGE_VISIT_)
#undef NIMBLE_RIG_MESSAGE_VISIT_
}

/// Calls f(MessageType<M>()) for the type M called `name` ("truth_state_t" or
/// "nimble.truth_state_t"). False (and f not called) if no message type has that name.
template <class F>
bool with_message_type(const std::string& name, F&& f) {
  const std::string bare = name.compare(0, 7, "nimble.") == 0 ? name.substr(7) : name;
#define NIMBLE_RIG_MESSAGE_FIND_(T)  \
  if (bare == #T) {                  \
    f(MessageType<T>());             \
    return true;                     \
  }
  NIMBLE_RIG_MESSAGES(NIMBLE_RIG_MESSAGE_FIND_)
#undef NIMBLE_RIG_MESSAGE_FIND_
  return false;
}

/// The number of message types.
constexpr int kRigMessageCount = 0
#define NIMBLE_RIG_MESSAGE_COUNT_(T) +1
    NIMBLE_RIG_MESSAGES(NIMBLE_RIG_MESSAGE_COUNT_)
#undef NIMBLE_RIG_MESSAGE_COUNT_
    ;

}  // namespace nimble
)";

std::string header(const std::vector<LcmStruct>& types) {
  std::ostringstream out;
  out << "// Generated at build time by rig_message_list_gen (lcmtypes/message_list_gen.cc) from\n"
      << "// lcmtypes/*.lcm: do not edit.\n"
      << "#pragma once\n"
      << "/// The rig's message types, one list generated from their .lcm files: every type\n"
      << "/// (NIMBLE_RIG_MESSAGES, for_each_message_type, with_message_type) and every field of each\n"
      << "/// (MessageFields, for_each_field, bind_fields). docs/contract.md says what uses it.\n\n"
      << "#include <string>\n"
      << "#include <type_traits>\n\n";
  for (const auto& s : types) out << "#include <" << s.package << "/" << s.name << ".hpp>\n";
  out << "\n/// Every message type, in the order of their files: X(type) for each (package nimble).\n"
      << "#define NIMBLE_RIG_MESSAGES(X)";
  for (const auto& s : types) out << " \\\n  X(" << s.name << ")";
  out << "\n\n/// Every message type, separated by commas (for a list of template arguments).\n"
      << "#define NIMBLE_RIG_MESSAGE_TYPES";
  for (std::size_t i = 0; i < types.size(); ++i) {
    out << (i == 0 ? " " : ", ") << types[i].package << "::" << types[i].name;
  }
  out << "\n" << kPrologue;
  for (const auto& s : types) write_type(out, s);
  out << kEpilogue;
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: rig_message_list_gen <output header> <file.lcm>...\n");
    return 2;
  }
  try {
    std::vector<LcmStruct> types;
    for (int i = 2; i < argc; ++i) {
      const std::string path = argv[i];
      const std::string name = path.substr(path.find_last_of('/') + 1);
      std::vector<LcmStruct> parsed = nimble::lcmjson::parse_lcm(read_file(path), name);
      if (parsed.size() != 1 || parsed[0].package != "nimble" || parsed[0].name + ".lcm" != name) {
        throw std::runtime_error(path + ": not one struct of package nimble named like the file");
      }
      types.push_back(std::move(parsed[0]));
    }
    const std::string text = header(types);
    const std::string out_path = argv[1];
    std::ofstream out(out_path, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + out_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rig_message_list_gen: %s\n", e.what());
    return 1;
  }
  return 0;
}
