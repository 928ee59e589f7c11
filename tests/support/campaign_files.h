#pragma once
/// Test helpers for `rig sweep` campaigns: a campaign's merged result with the fields that say
/// where and how it ran taken out (the JSON's `machine` objects, the CSV's machine_* columns),
/// so that results of different backends, jobs and chunk sizes compare byte for byte.

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace nimble::test {

/// The JSON text of `file` without any `machine` member, at any depth, in the writer's order.
inline std::string json_without_machine(const std::string& file) {
  std::ifstream in(file);
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(in);
  const auto strip = [](auto& self, nlohmann::ordered_json& node) -> void {
    if (node.is_object()) {
      node.erase("machine");
      for (auto& item : node.items()) self(self, item.value());
    } else if (node.is_array()) {
      for (auto& item : node) self(self, item);
    }
  };
  strip(strip, j);
  return j.dump(1);
}

/// The fields of one CSV line (RFC 4180 quoting).
inline std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t k = 0; k < line.size(); ++k) {
    const char c = line[k];
    if (quoted) {
      if (c == '"' && k + 1 < line.size() && line[k + 1] == '"') {
        fields.back() += "\"\"";
        ++k;
      } else if (c == '"') {
        quoted = false;
        fields.back() += c;
      } else {
        fields.back() += c;
      }
    } else if (c == ',') {
      fields.emplace_back();
    } else {
      if (c == '"') quoted = true;
      fields.back() += c;
    }
  }
  return fields;
}

/// The CSV text of `file` without its machine_* columns (each field as written).
inline std::string csv_without_machine(const std::string& file) {
  std::ifstream in(file);
  std::string line, out;
  std::vector<bool> keep;
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = csv_fields(line);
    if (keep.empty()) {
      for (const auto& f : fields) keep.push_back(f.rfind("machine_", 0) != 0);
    }
    std::string row;
    for (std::size_t k = 0; k < fields.size() && k < keep.size(); ++k) {
      if (keep[k]) row += (row.empty() ? "" : ",") + fields[k];
    }
    out += row + "\n";
  }
  return out;
}

/// Runs a shell command; its exit code (-1 if it did not exit).
inline int shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace nimble::test
