// The run's JSON report (launcher/run_report.h, report_json(); `rig run --json`): each part of
// the report with its function over nlohmann::ordered_json (keys in the order written, numbers
// as the shortest text that reads back to the same double, a non-finite number as null). The
// keys and their order are the report's format (docs/tool.md, "rig run --json").

#include <algorithm>

#include "launcher/run_report.h"
#include "core/json_line.h"

namespace nimble::launcher {
namespace {

/// The run's roll tracking and its oscillation (a run with a controller).
OrderedJson tracking_json(const RunReport& r) {
  const TrackingSummary& t = r.tracking;
  const Oscillation& o = r.verdict.tracking.oscillation;
  return {{"samples", t.samples},
          {"rms_deg", t.rms_deg},
          {"max_deg", t.max_deg},
          {"max_at_s", t.max_at_s},
          {"lost", r.verdict.tracking.lost},
          {"oscillation",
           {{"detected", o.detected},
            {"kind", !o.detected ? ""
                     : o.growing ? "growing"
                                 : "sustained"},
            {"frequency_hz", o.frequency_hz},
            {"amplitude_deg", o.amplitude_deg},
            {"damping_ratio", o.damping_ratio},
            {"start_s", o.start_s},
            {"cycles", o.cycles}}}};
}

/// One side of the CAN bridge: what it carried and what it rejected.
OrderedJson can_json(const nimble::CanHealth& h) {
  return {{"interface", h.interface_name},
          {"messages_to_can", h.messages_to_can},
          {"messages_to_lcm", h.messages_to_lcm},
          {"frames_sent", h.frames_sent},
          {"frames_received", h.frames_received},
          {"fd", h.fd != 0},
          {"fd_frames_sent", h.fd_frames_sent},
          {"fd_frames_received", h.fd_frames_received},
          {"rejected_unknown_id", h.rejected_unknown_id},
          {"rejected_wrong_length", h.rejected_wrong_length},
          {"rejected_bad_checksum", h.rejected_bad_checksum},
          {"rejected_stale_counter", h.rejected_stale_counter},
          {"rejected_out_of_range", h.rejected_out_of_range},
          {"counter_gaps", h.counter_gaps},
          {"saturated_values", h.saturated_values},
          {"error_frames", h.error_frames},
          {"bus_state", static_cast<int>(h.bus_state)},
          {"last_error", h.last_error},
          {"send_enobufs", h.send_enobufs},
          {"send_retries", h.send_retries},
          {"send_dropped", h.send_dropped},
          {"receive_dropped", h.receive_dropped},
          {"candump_file", h.candump_file},
          {"candump_lines", h.candump_lines}};
}

/// The flight's extremes, ranges, final state, vertical excursion and its trace where kept, into `j`.
void add_flight(OrderedJson& j, const FlightSummary& f) {
  j["max_abs"] = {{"p", f.max_abs_p},
                  {"v", f.max_abs_v},
                  {"phi", f.max_abs_phi},
                  {"theta", f.max_abs_theta},
                  {"psi", f.max_abs_psi}};
  j["ranges"] = {{"p", f.max_p - f.min_p},
                 {"v", f.max_v - f.min_v},
                 {"phi", f.max_phi - f.min_phi},
                 {"delta_f", f.max_df - f.min_df}};
  j["final"] = {{"p", f.final_p}, {"v", f.final_v}, {"phi", f.final_phi}};
  j["vertical"] = {{"height_min_m", f.min_height_m},
                   {"height_max_m", f.max_height_m},
                   {"height_final_m", f.final_height_m},
                   {"max_abs_height_change_m", f.max_abs_height_change_m()},
                   {"w_min_mps", f.min_w},
                   {"w_max_mps", f.max_w},
                   {"w_initial_mps", f.initial_w}};
  if (f.trace_dt_s > 0) {
    j["trace"] = {{"dt_s", f.trace_dt_s}, {"p", f.trace_p}, {"v", f.trace_v}, {"phi", f.trace_phi}};
  }
}

OrderedJson estimator_json(const EstimatorSummary& est) {
  return {{"samples", est.samples},
          {"phi_rms_deg", est.phi_rms_deg},
          {"phi_max_deg", est.phi_max_deg},
          {"p_rms_radps", est.p_rms_radps},
          {"v_rms_mps", est.v_rms_mps},
          {"poses_accepted", est.poses_accepted},
          {"poses_rejected", est.poses_rejected},
          {"poses_missing", est.poses_missing},
          {"poses_too_old", est.poses_too_old},
          {"poses_too_new", est.poses_too_new},
          {"velocity_windows_uncovered", est.velocity_windows_uncovered},
          {"imu_rejected", est.imu_rejected},
          {"imu_gaps", est.imu_gaps}};
}

OrderedJson channels_json(const RunReport& r) {
  OrderedJson j = OrderedJson::object();
  for (const auto& [name, c] : r.channels) {
    j[name] = {{"count", c.count},
               {"rate_hz", c.rate_hz},
               {"expected_hz", c.expected_hz},
               {"drops", c.drops},
               {"late", c.late},
               {"malformed", c.malformed},
               {"rate_basis", c.wall_clock ? "wall" : "sim"}};
  }
  return j;
}

/// Each process's loop timing, message latency and what it received.
OrderedJson timing_json(const RunReport& r) {
  OrderedJson j = OrderedJson::object();
  for (const auto& [name, t] : r.timing) {
    OrderedJson received = OrderedJson::object();
    for (const auto& [channel, rc] : t.received) received[channel] = {{"count", rc.count}, {"late", rc.late}};
    OrderedJson stages = OrderedJson::array();
    for (const TimingSummary::Stage& st : t.stages) {
      stages.push_back({{"stage", st.name},
                        {"count", st.count},
                        {"p50_us", st.p50_us},
                        {"p99_us", st.p99_us},
                        {"max_us", st.max_us}});
    }
    j[name] = {{"loop_rate_hz", t.loop_rate_hz},
               {"loop_count", t.loop_count},
               {"overruns", t.overruns},
               {"jitter_p50_us", t.jitter_p50_us},
               {"jitter_p99_us", t.jitter_p99_us},
               {"jitter_max_us", t.jitter_max_us},
               {"latency_count", t.latency_count},
               {"latency_p50_us", t.latency_p50_us},
               {"latency_p99_us", t.latency_p99_us},
               {"latency_max_us", t.latency_max_us},
               {"received", std::move(received)},
               {"stages", std::move(stages)}};
  }
  return j;
}

/// Every fault, each process with how it ended, and the hosts they ran on, into `j`.
void add_faults_processes_hosts(OrderedJson& j, const RunReport& r) {
  j["faults"] = OrderedJson::array();
  for (const auto& fr : r.faults) {
    j["faults"].push_back({{"process", fr.process},
                           {"severity", fr.severity},
                           {"code", fr.code},
                           {"channel", fr.channel},
                           {"message", fr.message},
                           {"rig_time_s", fr.rig_time_s}});
  }
  j["processes"] = OrderedJson::object();
  for (const auto& p : r.processes) {
    OrderedJson& out = j["processes"][p.name];
    out = {{"pid", p.pid}, {"exit_code", p.exit_code}, {"signal", p.signal}, {"heartbeats", p.heartbeats}};
    if (!p.python.empty()) out["python"] = p.python;
    for (const HostSummary& h : r.hosts) {
      if (std::find(h.processes.begin(), h.processes.end(), p.name) != h.processes.end()) out["host"] = h.name;
    }
  }
  if (r.hosts.empty()) return;
  for (const HostSummary& h : r.hosts) {
    j["hosts"][h.name] = {{"launcher", h.launcher},
                          {"address", h.address},
                          {"network_namespace", h.network_namespace},
                          {"processes", h.processes}};
  }
}

}  // namespace

std::string report_json(const RunReport& r) {
  OrderedJson j = {{"scenario", r.scenario},           {"clock", r.clock},       {"seed", r.seed},
                   {"config_digest", r.config_digest}, {"lcm_url", r.transport}, {"log", r.log_file}};
  if (!r.log.file.empty()) {
    j["log_kept"] = {
        {"events", r.log.events}, {"bytes", r.log.bytes}, {"sim_time_s", r.log.sim_time_s}, {"failure", r.log.failure}};
  }
  j["controlled"] = r.verdict.controlled;
  j["returned_to_hover"] = r.verdict.hover;
  j["exit_code"] = r.verdict.exit_code;
  j["result"] = r.verdict.text;
  if (r.verdict.timing.judged) {
    const TimingVerdict& tv = r.verdict.timing;
    j["realtime_health"] = {{"degraded", tv.degraded},
                            {"worst_process", tv.worst},
                            {"worst_fraction", tv.worst_fraction},
                            {"text", tv.text}};
  }
  j["sim_time_s"] = r.sim_time_s;
  j["wall_time_s"] = r.wall_time_s;
  j["speed_x_realtime"] = r.speed_x_realtime();
  add_flight(j, r.flight);
  if (r.estimator.samples > 0) j["estimator"] = estimator_json(r.estimator);
  if (r.tracking.samples > 0) j["tracking"] = tracking_json(r);
  if (!r.can_health.empty()) {
    for (const auto& [name, h] : r.can_health) j["can"][name] = can_json(h);
  }
  j["channels"] = channels_json(r);
  j["timing"] = timing_json(r);
  add_faults_processes_hosts(j, r);
  for (const TapFigures& t : r.taps) {
    OrderedJson& tap = j[t.key];
    tap = OrderedJson::object();
    for (const auto& v : t.values) tap[v.first] = v.second;
    if (!t.note.empty()) tap["note"] = t.note;
  }
  return json_line(j);
}

}  // namespace nimble::launcher
