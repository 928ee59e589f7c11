#include "ident/flight_data.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/input_file.h"
#include "core/output_file.h"

namespace nimble::ident {
namespace {

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\t' || s[a] == '\r')) ++a;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\t' || s[b - 1] == '\r')) --b;
  return s.substr(a, b - a);
}

std::vector<std::string> split_cells(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return cells;
}

std::string join(const std::vector<std::string>& xs) {
  std::string out;
  for (std::size_t i = 0; i < xs.size(); ++i) out += (i ? ", " : "") + xs[i];
  return out;
}

std::string format_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

}  // namespace

const std::vector<ChannelSpec>& channel_specs() {
  static const std::vector<ChannelSpec> specs{
      {"t", "s", true, "time"},
      {"p", "rad/s", true, "roll rate (body x)"},
      {"q", "rad/s", false, "pitch rate (body y)"},
      {"r", "rad/s", false, "yaw rate (body z)"},
      {"u", "m/s", false, "forward velocity (body x)"},
      {"v", "m/s", true, "lateral velocity (body y)"},
      {"w", "m/s", false, "vertical velocity (body z)"},
      {"phi", "rad", true, "roll angle"},
      {"theta", "rad", false, "pitch angle"},
      {"psi", "rad", false, "yaw angle"},
      {"delta_f", "rad/s", true, "flapping-frequency difference left - right"},
      {"delta_t", "%", true, "throttle, deviation from trim"},
      {"delta_d", "rad", false, "dihedral"},
      {"delta_w", "rad", false, "wing root"},
      {"ax", "m/s^2", false, "specific force (body x)"},
      {"ay", "m/s^2", false, "specific force (body y)"},
      {"az", "m/s^2", false, "specific force (body z)"},
      {"phi_sp", "rad", false, "roll-angle set-point"},
      {"delta_f_cmd", "rad/s", false,
       "flapping-frequency difference commanded by the flight board (flap actuator input)"},
  };
  return specs;
}

const ChannelSpec& channel_spec(const std::string& name) {
  for (const auto& s : channel_specs()) {
    if (s.name == name) return s;
  }
  throw std::out_of_range("unknown flight-data channel '" + name + "'");
}

bool is_known_channel(const std::string& name) {
  if (name == "t") return false;
  for (const auto& s : channel_specs()) {
    if (s.name == name) return true;
  }
  return false;
}

const Channel& FlightData::at(const std::string& name) const {
  const auto it = channels.find(name);
  if (it == channels.end()) {
    throw std::out_of_range(source + ": no channel '" + name + "'");
  }
  return it->second;
}

std::size_t FlightData::min_samples() const {
  if (channels.empty()) return 0;
  std::size_t n = static_cast<std::size_t>(-1);
  for (const auto& [name, c] : channels) n = std::min(n, c.values.size());
  return n;
}

FlightData parse_flight_csv(const std::string& text, const std::string& source) {
  // A UTF-8 byte order mark (spreadsheet programs write one) is not part of the first name.
  const bool bom = text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0;
  std::istringstream in(bom ? text.substr(3) : text);
  std::string line;
  int line_no = 0;

  // Comment lines, then the header.
  std::vector<std::string> header;
  int header_line = -1;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    header = split_cells(t);
    // Names in double quotes (as spreadsheet programs export them) are the names without them.
    for (auto& name : header) {
      if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = trim(name.substr(1, name.size() - 2));
    }
    header_line = line_no;
    break;
  }
  if (header_line < 0) throw DataError(source, -1, -1, "", "no header row (the file is empty or only comments)");

  std::vector<std::string> unknown, missing;
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string& name = header[i];
    if (name.empty()) {
      throw DataError(source, header_line, -1, "", "header cell " + std::to_string(i + 1) + " is empty");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (header[j] == name) throw DataError(source, header_line, -1, name, "column appears twice in the header");
    }
    if (name != "t" && !is_known_channel(name)) unknown.push_back(name);
  }
  if (!unknown.empty()) {
    std::vector<std::string> known;
    for (const auto& s : channel_specs()) known.push_back(s.name);
    throw DataError(source, header_line, -1, unknown.front(),
                    std::string(unknown.size() == 1 ? "unknown column" : "unknown columns") + " " + join(unknown) +
                        " (known: " + join(known) + ")");
  }
  for (const auto& s : channel_specs()) {
    if (!s.required) continue;
    bool found = false;
    for (const auto& h : header) found = found || h == s.name;
    if (!found) missing.push_back(s.name);
  }
  if (!missing.empty()) {
    throw DataError(source, header_line, -1, missing.front(),
                    std::string(missing.size() == 1 ? "missing required column" : "missing required columns") + " " +
                        join(missing));
  }

  std::vector<std::vector<double>> columns(header.size());
  std::size_t t_index = 0;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == "t") t_index = i;
  }
  int row = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty()) continue;
    ++row;
    const std::vector<std::string> cells = split_cells(t);
    if (cells.size() != header.size()) {
      throw DataError(
          source, line_no, row, "",
          "has " + std::to_string(cells.size()) + " cells, the header has " + std::to_string(header.size()));
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const std::string& cell = cells[i];
      if (cell.empty()) throw DataError(source, line_no, row, header[i], "empty cell");
      errno = 0;
      char* end = nullptr;
      const double x = std::strtod(cell.c_str(), &end);
      if (end == cell.c_str() || *end != '\0') {
        throw DataError(source, line_no, row, header[i], "value '" + cell + "' is not a number");
      }
      if (!std::isfinite(x) || errno == ERANGE) {
        throw DataError(source, line_no, row, header[i], "value '" + cell + "' is not a finite number");
      }
      columns[i].push_back(x);
    }
    const std::vector<double>& time = columns[t_index];
    if (time.size() >= 2 && !(time.back() > time[time.size() - 2])) {
      throw DataError(source, line_no, row, "t",
                      "time " + cells[t_index] + " s does not increase (previous row " +
                          format_number(time[time.size() - 2]) + " s)");
    }
  }
  if (row < 2) {
    throw DataError(source, -1, -1, "", "has " + std::to_string(row) + " data rows, needs at least 2");
  }

  FlightData data;
  data.source = source;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (i == t_index) continue;
    Channel c;
    c.t_s = columns[t_index];
    c.values = std::move(columns[i]);
    data.channels.emplace(header[i], std::move(c));
  }
  return data;
}

FlightData read_flight_csv(const std::string& file) {
  std::string text;
  try {
    text = read_input_file(file, InputKind::kRecord);  // a regular file within a record's bound
  } catch (const InputFileError& e) {
    throw DataError(file, -1, -1, "", e.problem());
  }
  return parse_flight_csv(text, file);
}

std::string format_flight_csv(const FlightData& data) {
  std::vector<std::string> names;
  for (const auto& s : channel_specs()) {
    if (s.name == "t") continue;
    if (data.has(s.name)) {
      names.push_back(s.name);
    } else if (s.required) {
      throw std::invalid_argument(data.source + ": cannot write CSV without required channel '" + s.name + "'");
    }
  }
  for (const auto& [name, c] : data.channels) {
    if (!is_known_channel(name)) throw std::invalid_argument(data.source + ": unknown channel '" + name + "'");
  }
  const std::vector<double>& t = data.at(names.front()).t_s;
  for (const auto& name : names) {
    const Channel& c = data.at(name);
    if (c.t_s != t || c.values.size() != t.size()) {
      throw std::invalid_argument(data.source + ": channel '" + name +
                                  "' has its own time stamps; resample to one grid before writing CSV");
    }
  }
  std::ostringstream out;
  out << "# units: t [s]";
  for (const auto& name : names) out << ", " << name << " [" << channel_spec(name).unit << "]";
  out << "\nt";
  for (const auto& name : names) out << "," << name;
  out << "\n";
  for (std::size_t k = 0; k < t.size(); ++k) {
    out << format_number(t[k]);
    for (const auto& name : names) out << "," << format_number(data.at(name).values[k]);
    out << "\n";
  }
  return out.str();
}

void write_flight_csv(const FlightData& data, const std::string& file) { write_file(file, format_flight_csv(data)); }

namespace {

/// Checks sample k (0-based) of the time stamps `t_s` of `column`: finite, and after the one before.
void check_time_at(const std::string& source, const std::string& column, const std::vector<double>& t_s,
                   std::size_t k) {
  const int sample = static_cast<int>(k) + 1;
  if (!std::isfinite(t_s[k])) throw DataError(source, -1, sample, column, "sample is not a finite number");
  if (k > 0 && !(t_s[k] > t_s[k - 1])) {
    throw DataError(
        source, -1, sample, column,
        "time " + format_number(t_s[k]) + " s does not increase (previous " + format_number(t_s[k - 1]) + " s)");
  }
}

}  // namespace

FlightData flight_data_from_columns(const std::string& source, const std::vector<double>& t_s,
                                    std::map<std::string, std::vector<double>> columns) {
  for (std::size_t k = 0; k < t_s.size(); ++k) check_time_at(source, "t", t_s, k);
  FlightData out;
  out.source = source;
  for (auto& [name, values] : columns) {
    if (!is_known_channel(name)) {
      std::vector<std::string> known;
      for (const auto& spec : channel_specs()) {
        if (spec.name != "t") known.push_back(spec.name);
      }
      throw std::invalid_argument(source + ": unknown channel '" + name + "' (known: " + join(known) + ")");
    }
    if (values.size() != t_s.size()) {
      throw std::invalid_argument(source + ": '" + name + "' has " + std::to_string(values.size()) +
                                  " samples, 't' has " + std::to_string(t_s.size()));
    }
    out.channels[name] = Channel{t_s, std::move(values)};
  }
  for (const auto& spec : channel_specs()) {
    if (spec.required && spec.name != "t" && !out.has(spec.name)) {
      throw DataError(source, -1, -1, spec.name, "missing required channel '" + spec.name + "'");
    }
  }
  validate_flight_data(out);
  return out;
}

void validate_flight_data(const FlightData& data) {
  for (const auto& [name, c] : data.channels) {
    if (c.t_s.size() != c.values.size()) {
      throw DataError(data.source, -1, -1, name,
                      std::to_string(c.values.size()) + " values but " + std::to_string(c.t_s.size()) + " time stamps");
    }
    for (std::size_t k = 0; k < c.values.size(); ++k) {
      if (!std::isfinite(c.values[k])) {
        throw DataError(data.source, -1, static_cast<int>(k) + 1, name, "sample is not a finite number");
      }
      check_time_at(data.source, name, c.t_s, k);
    }
  }
}

}  // namespace nimble::ident
