// The DBC file and the codec's constants describe the same layout: this parses
// can_bridge/nimble_rig.dbc (BU_, BO_, SG_, CM_, VAL_, BA_ lines) and compares every message and
// signal with frame_layout.h, so neither can change without the other.

#include <linux/can.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "can_bridge/frame_layout.h"
#include "can_bridge/signal_codec.h"

using namespace nimble::can;

namespace {

struct DbcSignal {
  std::string name;
  unsigned start = 0, length = 0;
  bool little_endian = false, is_signed = false;
  double factor = 0, offset = 0, min = 0, max = 0;
  std::string unit, receivers;
};

struct DbcMessage {
  uint32_t id = 0;
  std::string name, transmitter;
  unsigned dlc = 0;
  std::vector<DbcSignal> signals;
};

struct Dbc {
  std::vector<std::string> nodes;
  std::map<uint32_t, DbcMessage> messages;
  std::vector<std::string> lines;
};

Dbc load_dbc() {
  const std::string path = std::string(RIG_SOURCE_DIR) + "/can_bridge/nimble_rig.dbc";
  std::ifstream in(path);
  REQUIRE(in.good());
  const std::regex bu(R"(^BU_:\s*(.*)$)");
  const std::regex bo(R"(^BO_ (\d+) (\w+): (\d+) (\w+)\s*$)");
  const std::regex sg(
      R"re(^ SG_ (\w+) : (\d+)\|(\d+)@([01])([+-]) \(([-+0-9.eE]+),([-+0-9.eE]+)\) \[([-+0-9.eE]+)\|([-+0-9.eE]+)\] "([^"]*)" (\w+(?:,\w+)*)\s*$)re");
  Dbc dbc;
  DbcMessage* current = nullptr;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    dbc.lines.push_back(line);
    std::smatch m;
    if (std::regex_match(line, m, bu)) {
      std::istringstream names(m[1].str());
      for (std::string n; names >> n;) dbc.nodes.push_back(n);
    } else if (std::regex_match(line, m, bo)) {
      DbcMessage msg;
      msg.id = static_cast<uint32_t>(std::stoul(m[1]));
      msg.name = m[2];
      msg.dlc = static_cast<unsigned>(std::stoul(m[3]));
      msg.transmitter = m[4];
      INFO("line " << line_no);
      REQUIRE(dbc.messages.count(msg.id) == 0);
      current = &(dbc.messages[msg.id] = msg);
    } else if (line.rfind(" SG_", 0) == 0) {
      INFO("line " << line_no << ": " << line);
      REQUIRE(std::regex_match(line, m, sg));  // every signal line has the full syntax
      REQUIRE(current != nullptr);
      DbcSignal s;
      s.name = m[1];
      s.start = static_cast<unsigned>(std::stoul(m[2]));
      s.length = static_cast<unsigned>(std::stoul(m[3]));
      s.little_endian = m[4] == "1";
      s.is_signed = m[5] == "-";
      s.factor = std::stod(m[6]);
      s.offset = std::stod(m[7]);
      s.min = std::stod(m[8]);
      s.max = std::stod(m[9]);
      s.unit = m[10];
      s.receivers = m[11];
      current->signals.push_back(s);
    } else if (line.empty()) {
      current = nullptr;
    }
  }
  return dbc;
}

const SignalSpec* find_signal(const std::string& name) {
  for (const SignalSpec& s : kAllSignals) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

}  // namespace

TEST_CASE("the DBC file has the codec's messages", "[dbc]") {
  const Dbc dbc = load_dbc();
  REQUIRE(dbc.messages.size() == kAllFrames.size());
  const std::set<std::string> nodes(dbc.nodes.begin(), dbc.nodes.end());
  for (const FrameSpec& f : kAllFrames) {
    INFO(f.name);
    REQUIRE(dbc.messages.count(f.id) == 1);
    const DbcMessage& m = dbc.messages.at(f.id);
    CHECK(m.name == f.name);
    CHECK(m.dlc == f.length_bytes);
    CHECK(m.transmitter == f.transmitter);
    CHECK(nodes.count(m.transmitter) == 1);
    CHECK(f.id <= CAN_SFF_MASK);
  }
}

TEST_CASE("the DBC file's signals equal the codec's constants", "[dbc]") {
  const Dbc dbc = load_dbc();
  const std::set<std::string> nodes(dbc.nodes.begin(), dbc.nodes.end());
  std::size_t seen = 0;
  for (const auto& [id, m] : dbc.messages) {
    for (const DbcSignal& d : m.signals) {
      INFO(m.name << "." << d.name);
      const SignalSpec* s = find_signal(d.name);
      REQUIRE(s != nullptr);
      ++seen;
      CHECK(s->frame_id == id);
      CHECK(d.start == s->start_bit);
      CHECK(d.length == s->length_bits);
      CHECK(d.little_endian);
      CHECK(d.is_signed == s->is_signed);
      CHECK(d.factor == Approx(s->factor).epsilon(1e-12));
      CHECK(d.offset == Approx(s->offset).margin(1e-12));
      CHECK(d.min == Approx(s->min).margin(1e-9));
      CHECK(d.max == Approx(s->max).margin(1e-9));
      CHECK(d.unit == s->unit);
      CHECK(nodes.count(d.receivers) == 1);
      CHECK(d.receivers != m.transmitter);
    }
  }
  CHECK(seen == kAllSignals.size());
}

TEST_CASE("every frame's signals fit, do not overlap and end in counter and CRC", "[dbc]") {
  for (const FrameSpec& f : kAllFrames) {
    INFO(f.name);
    std::vector<int> owner(8 * f.length_bytes, 0);
    bool has_counter = false, has_crc = false;
    for (const SignalSpec& s : kAllSignals) {
      if (s.frame_id != f.id) continue;
      INFO(s.name);
      REQUIRE(s.start_bit + s.length_bits <= 8u * f.length_bytes);
      for (unsigned b = s.start_bit; b < s.start_bit + s.length_bits; ++b) CHECK(++owner[b] == 1);
      // the documented physical range is representable in the raw bits
      const double lo = s.is_signed ? -std::ldexp(1.0, s.length_bits - 1) : 0.0;
      const double hi = s.is_signed ? std::ldexp(1.0, s.length_bits - 1) - 1 : std::ldexp(1.0, s.length_bits) - 1;
      CHECK(static_cast<double>(raw_min(s)) >= lo);
      CHECK(static_cast<double>(raw_max(s)) <= hi);
      CHECK(raw_min(s) <= raw_max(s));
      if (s.start_bit == 8 * kCounterByte + 4 && s.length_bits == 4) has_counter = true;
      if (s.start_bit == 8 * kCrcByte && s.length_bits == 8) has_crc = true;
    }
    CHECK(has_counter);
    CHECK(has_crc);
  }
}

TEST_CASE("the DBC file's comments, value tables and attributes refer to what exists", "[dbc]") {
  const Dbc dbc = load_dbc();
  const std::regex ref(R"(^(?:CM_ SG_|VAL_) (\d+) (\w+) .*;\s*$)");
  const std::regex msg_ref(R"(^(?:CM_ BO_|BA_ "\w+" BO_) (\d+) .*;\s*$)");
  int refs = 0;
  for (const std::string& line : dbc.lines) {
    std::smatch m;
    INFO(line);
    if (std::regex_match(line, m, ref)) {
      ++refs;
      const uint32_t id = static_cast<uint32_t>(std::stoul(m[1]));
      REQUIRE(dbc.messages.count(id) == 1);
      bool found = false;
      for (const DbcSignal& s : dbc.messages.at(id).signals) found |= s.name == m[2].str();
      CHECK(found);
    } else if (std::regex_match(line, m, msg_ref)) {
      ++refs;
      CHECK(dbc.messages.count(static_cast<uint32_t>(std::stoul(m[1]))) == 1);
    }
  }
  CHECK(refs > static_cast<int>(kAllSignals.size()));
  CHECK(dbc.lines.front() == "VERSION \"1.0\"");
}
