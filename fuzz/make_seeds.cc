// Writes the seed corpora of the fuzz targets (fuzz/corpus/<target>/) from the rig itself: the
// messages of a short in-process flight (every channel, over the CAN link), frames of the CAN
// codec, candump lines, a flight CSV, the shipped model and scenario files, and a short LCM log.
//
//   build-san/bin/make_fuzz_seeds fuzz/corpus
//
// Each corpus stays a few kilobytes. Run it again after a message or format change.

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <linux/can/error.h>

#include <lcm/lcm-cpp.hpp>

#include "can_bridge/candump_log.h"
#include "can_bridge/codec.h"
#include "contract/channels.h"
#include "ident/flight_data.h"
#include "lcmlog/lcm_log.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include <nimble/fault_event_t.hpp>

namespace fs = std::filesystem;
using namespace nimble;

namespace {

const std::string kSource = RIG_SOURCE_DIR;

void write(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out << bytes;
  if (!out) throw std::runtime_error("cannot write " + (dir / name).string());
}

std::string bytes_of(const std::vector<uint8_t>& v) { return std::string(v.begin(), v.end()); }

/// One record of the node harness (node_harness.h): selector, length, payload.
std::string record(std::size_t selector, const std::vector<uint8_t>& payload) {
  std::string r;
  r += static_cast<char>(selector);
  r += static_cast<char>(payload.size() & 0xFF);
  r += static_cast<char>((payload.size() >> 8) & 0xFF);
  return r + bytes_of(payload);
}

std::size_t selector_of(const std::string& channel) {
  const auto& table = contract::channel_table();
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (table[i].name == channel) return i;
  }
  throw std::runtime_error("no channel " + channel);
}

/// One 15-byte record of fuzz_can_frame: identifier, length, control (0: keep the CRC), data, value seed.
std::string frame_record(const can_frame& f) {
  std::string r(15, '\0');
  std::memcpy(r.data(), &f.can_id, 4);
  r[4] = static_cast<char>(f.len);
  std::memcpy(r.data() + 6, f.data, 8);
  return r;
}

/// fuzz_can_frame and fuzz_candump: the rig's command and feedback frames, an error frame, a CAN
/// FD frame and a remote frame.
void write_can_seeds(const fs::path& out) {
  // ---------------------------------------------------------------------------
  can::CommandEncoder commands;
  can::FeedbackEncoder feedback;
  std::string frames, candump;
  int64_t t_ns = 1700000000123456000LL;
  for (int i = 0; i < 3; ++i) {
    actuator_command_t cmd{};
    cmd.seq = 100 + i;
    cmd.mode = actuator_command_t::MODE_DELTA_F;
    cmd.flap_freq_collective_radps = 102.5;
    cmd.delta_f_radps = 10.0 * i;
    cmd.throttle_pct = 40.0;
    cmd.dihedral_rad = 0.1;
    cmd.wing_root_rad = -0.05;
    cmd.rolling_counter = static_cast<int8_t>(i + 1);
    for (const can_frame& f : commands.encode(cmd)) {
      frames += frame_record(f);
      candump += can::format_candump_line(f, t_ns += 1000000, "vcan0") + "\n";
    }
    actuator_feedback_t fb{};
    fb.flap_freq_left_radps = 103.0;
    fb.flap_freq_right_radps = 102.0;
    fb.throttle_pct = -3.0;
    fb.cmd_seq = 100 + i;
    fb.cmd_age_us = 1500;
    for (const can_frame& f : feedback.encode(fb)) {
      frames += frame_record(f);
      candump += can::format_candump_line(f, t_ns += 1000000, "vcan0") + "\n";
    }
  }
  write(out / "fuzz_can_frame", "command_and_feedback", frames);
  can_frame error{};
  error.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_CNT;
  error.len = CAN_ERR_DLC;
  error.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  error.data[6] = 128;
  write(out / "fuzz_can_frame", "error_frame", frame_record(error));
  candump += can::format_candump_line(error, t_ns += 1000000, "vcan0") + "\n";
  canfd_frame fd{};
  fd.can_id = 0x101;
  fd.len = 12;
  fd.flags = CANFD_BRS;
  for (int i = 0; i < 12; ++i) fd.data[i] = static_cast<uint8_t>(i * 17);
  candump += can::format_candump_line(fd, t_ns += 1000000, "vcan1") + "\n";
  candump += "(1700000000.200000) vcan0 123#R\n";
  candump += "(1700000000.300000) vcan0 12345678#DEADBEEF\n";
  write(out / "fuzz_candump", "rig_frames", candump);
}

/// fuzz_flight_csv, fuzz_model_yaml and fuzz_scenario_yaml: a flight CSV and the shipped files.
void write_text_seeds(const fs::path& out) {
  // --- flight CSV -----------------------------------------------------------------------------
  ident::FlightData flight;
  flight.source = "seed";
  for (const char* name : {"p", "v", "phi", "delta_f", "delta_t", "phi_sp"}) {
    ident::Channel c;
    for (int i = 0; i < 4; ++i) {
      c.t_s.push_back(0.01 * i);
      c.values.push_back(0.1 * i - 0.05 + static_cast<double>(std::string(name).size()));
    }
    flight.channels[name] = c;
  }
  write(out / "fuzz_flight_csv", "flight", ident::format_flight_csv(flight));
  write(out / "fuzz_flight_csv", "comments_and_blank_lines",
        "# a flight\n# units\nt,p,v,phi,delta_f,delta_t\n\n0,1e-3,-2,0.5,3,4\n0.5,2E-3,-1,0.25,3,4\n");

  // --- model and scenario YAML: the shipped files -------------------------------------------
  for (const char* model : {"nimble_lateral_set1.yaml", "nimble_lateral4_yaw.yaml", "nimble_longitudinal.yaml",
                            "nimble_lateral_set1_kinematic.yaml"}) {
    std::ifstream in(kSource + "/rig_configs/models/" + model);
    write(out / "fuzz_model_yaml", model, std::string(std::istreambuf_iterator<char>(in), {}));
  }
  for (const char* scenario :
       {"hover.yaml", "id_doublet_train_fast.yaml", "coupled_doublet_6hz.yaml", "hover_turbulence.yaml"}) {
    std::ifstream in(kSource + "/rig_configs/" + scenario);
    write(out / "fuzz_scenario_yaml", scenario, std::string(std::istreambuf_iterator<char>(in), {}));
  }
  {
    // The hover scenario resolved (every section written out), with paths relative again.
    std::string resolved = to_yaml(load_scenario_tree(kSource + "/rig_configs/hover.yaml"));
    const std::string prefix = kSource + "/rig_configs/";
    for (std::size_t at; (at = resolved.find(prefix)) != std::string::npos;) resolved.erase(at, prefix.size());
    write(out / "fuzz_scenario_yaml", "hover_resolved.yaml", resolved);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_fuzz_seeds CORPUS_DIR\n";
    return 2;
  }
  const fs::path out = argv[1];
  const fs::path scratch = fs::temp_directory_path() / "rig-fuzz-seeds";
  fs::create_directories(scratch);

  // --- a short in-process flight over the CAN link: messages of every channel ---------------
  launcher::RunOptions options;
  options.scenario_file = kSource + "/rig_configs/hover.yaml";
  options.overrides = {parse_override("actuator_link=can"), parse_override("duration_s=0.05"),
                       parse_override("can_bridge.candump_log=false")};
  options.clock = launcher::kClockInprocess;
  const launcher::RunPlan plan = launcher::load_run_plan(options);
  launcher::InprocessOptions io;
  io.log_file = (scratch / "flight.lcmlog").string();
  (void)launcher::fly_inprocess(plan, io);

  // The first three messages of each channel, in log order.
  std::map<std::string, std::vector<std::vector<uint8_t>>> by_channel;
  std::vector<lcmlog::LogEventRecord> kept;
  {
    lcmlog::LcmLogReader reader(io.log_file);
    lcmlog::LogEventRecord ev;
    while (reader.next(&ev)) {
      auto& list = by_channel[ev.channel];
      if (list.size() >= 3) continue;
      list.push_back(ev.data);
      kept.push_back(ev);
    }
  }
  if (by_channel.count(contract::channels::kFault) == 0) {
    // A clean flight raises no fault: one written here.
    fault_event_t fault{};
    fault.seq = 0;
    fault.process = "plant";
    fault.severity = fault_event_t::SEVERITY_WARNING;
    fault.code = fault_event_t::CODE_COMMAND_TIMEOUT;
    fault.channel = contract::channels::kActuatorCommand;
    fault.message = "no command for 0.05 s: safe state";
    std::vector<uint8_t> bytes(static_cast<std::size_t>(fault.getEncodedSize()));
    fault.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    by_channel[contract::channels::kFault].push_back(bytes);
  }
  for (const auto& c : contract::channel_table()) {
    if (by_channel.count(c.name) == 0) std::cerr << "make_fuzz_seeds: the flight has no " << c.name << " message\n";
  }

  // fuzz_lcm_decode: one message of each channel (so each type the flight carries).
  for (const auto& [channel, list] : by_channel) write(out / "fuzz_lcm_decode", channel, bytes_of(list.front()));

  // Node targets: each channel's messages as records, and the lockstep sequence of the flight's
  // start (RUN_CONTROL, RIG_CLOCK ticks, inputs) as one input.
  const std::vector<std::string> nodes = {"fuzz_node_plant", "fuzz_node_controller", "fuzz_node_estimator",
                                          "fuzz_node_mocap", "fuzz_node_can_bridge"};
  std::string sequence;
  for (const auto& ev : kept) {
    if (sequence.size() < 3000) sequence += record(selector_of(ev.channel), ev.data);
  }
  for (const auto& node : nodes) {
    for (const auto& [channel, list] : by_channel) {
      std::string input;
      for (const auto& m : list) input += record(selector_of(channel), m);
      write(out / node, channel, input);
    }
    write(out / node, "sequence", sequence);
  }

  write_can_seeds(out);
  write_text_seeds(out);

  // --- a short LCM log: the kept messages -------------------------------------------------------
  {
    const std::string log = (scratch / "seed.lcmlog").string();
    {
      lcm::LogFile file(log, "w");
      for (const auto& ev : kept) {
        lcm::LogEvent e{};
        e.eventnum = ev.event_number;
        e.timestamp = ev.timestamp_us;
        e.channel = ev.channel;
        e.datalen = static_cast<int32_t>(ev.data.size());
        e.data = const_cast<uint8_t*>(ev.data.data());
        file.writeEvent(&e);
      }
    }
    std::ifstream in(log, std::ios::binary);
    write(out / "fuzz_lcm_log", "flight_start.lcmlog", std::string(std::istreambuf_iterator<char>(in), {}));
  }
  fs::remove_all(scratch);
  std::cout << "seed corpora written to " << out.string() << "\n";
  return 0;
}
