#include "launcher/run_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <ostream>

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <nimble/fault_event_t.hpp>

#include "contract/faults.h"
#include "core/json_writer.h"
#include "core/output_file.h"

namespace nimble::launcher {

void fill_from_monitor(RunReport& r, const RunMonitor& monitor, double sim_s, double wall_s) {
  r.sim_time_s = sim_s;
  r.wall_time_s = wall_s;
  r.channels = monitor.channels(sim_s, wall_s);
  r.timing = monitor.timing();
  r.flight = monitor.flight();
  r.estimator = monitor.estimator();
  r.tracking = monitor.tracking();
  r.can_health = monitor.can_health();
  r.faults = monitor.faults();
}

namespace {

/// The channels' counts and rates, then each process's loop timing and message latency.
void print_channels_and_timing(std::ostream& out, const RunReport& r) {
  out << "\nchannel              count    rate [Hz]  expected   drops   late  malformed\n";
  for (const auto& [name, c] : r.channels) {
    fmt::print(out, "{:<18} {:>8} {:>10.1f} {:>9.1f} {:>7} {:>6} {:>9}{}\n", name, c.count, c.rate_hz, c.expected_hz,
               c.drops, c.late, c.malformed, c.wall_clock ? "  (per wall second)" : "");
  }
  out << "\nloop timing "
      << (r.clock == kClockRealtime    ? "(wake-up jitter)"
          : r.clock == kClockInprocess ? "(in process: wall time per step, all processes)"
                                       : "(lockstep: wall time per step / per wait)")
      << "\nprocess        rate [Hz]    loops  overruns   p50 [us]   p99 [us]   max [us]\n";
  for (const auto& [name, t] : r.timing) {
    fmt::print(out, "{:<14} {:>9.1f} {:>8} {:>9} {:>10.1f} {:>10.1f} {:>10.1f}\n", name, t.loop_rate_hz, t.loop_count,
               t.overruns, t.jitter_p50_us, t.jitter_p99_us, t.jitter_max_us);
  }
  for (const auto& [name, t] : r.timing) {
    if (t.latency_count == 0) continue;
    const char* what = name == "plant"       ? "control loop latency (TRUTH published -> ACTUATOR_CMD received)"
                       : name == "estimator" ? "latency (IMU sample time -> ESTIMATE published)"
                                             : "latency";
    fmt::print(out, "{} {}: p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us over {} messages\n", name, what,
               t.latency_p50_us, t.latency_p99_us, t.latency_max_us, t.latency_count);
  }
}

/// The flight's extremes, ranges, final state and vertical excursion.
void print_flight(std::ostream& out, const RunReport& r) {
  const FlightSummary& f = r.flight;
  fmt::print(out, "\nflight     max |p| {:.4g} rad/s, max |v| {:.4g} m/s, max |phi| {:.4g} deg", f.max_abs_p,
             f.max_abs_v, f.max_abs_phi * 180 / M_PI);
  if (f.max_abs_theta > 0.0) fmt::print(out, ", max |theta| {:.4g} deg", f.max_abs_theta * 180 / M_PI);
  if (f.max_abs_psi > 0.0) fmt::print(out, ", max |psi| {:.4g} deg", f.max_abs_psi * 180 / M_PI);
  out << "\n";
  fmt::print(out, "ranges     p {:.2f} rad/s, v {:.2f} m/s, phi {:.2f} rad, delta_f {:.1f} rad/s\n", f.max_p - f.min_p,
             f.max_v - f.min_v, f.max_phi - f.min_phi, f.max_df - f.min_df);
  fmt::print(out, "final      p {:.3f} rad/s, v {:.3f} m/s, phi {:.2f} deg\n", f.final_p, f.final_v,
             f.final_phi * 180 / M_PI);
  fmt::print(out,
             "vertical   height {:+.2f} .. {:+.2f} m from the start (final {:+.2f} m), w {:.2f} .. {:.2f} m/s (initial "
             "{:.2f})\n",
             f.min_height_m, f.max_height_m, f.final_height_m, f.min_w, f.max_w, f.initial_w);
}

/// The estimator's errors and pose bookkeeping, and the roll tracking, where the run had them.
void print_estimator_and_tracking(std::ostream& out, const RunReport& r) {
  const EstimatorSummary& est = r.estimator;
  if (est.samples > 0) {
    fmt::print(
        out,
        "estimator  phi error rms {:.3f} deg (max {:.3f}), p error rms {:.4f} rad/s, v error rms {:.4f} m/s over {} "
        "estimates; poses accepted {}, rejected {}, missing {}\n",
        est.phi_rms_deg, est.phi_max_deg, est.p_rms_radps, est.v_rms_mps, est.samples, est.poses_accepted,
        est.poses_rejected, est.poses_missing);
    if (est.poses_too_old + est.poses_too_new + est.velocity_windows_uncovered + est.imu_rejected + est.imu_gaps > 0) {
      fmt::print(out,
                 "estimator  poses dropped {} too old, {} too new; velocity windows uncovered {}; IMU samples "
                 "rejected {}, gaps {}\n",
                 est.poses_too_old, est.poses_too_new, est.velocity_windows_uncovered, est.imu_rejected, est.imu_gaps);
    }
  }
  if (r.tracking.samples > 0) {
    const Oscillation& o = r.verdict.tracking.oscillation;
    fmt::print(out, "tracking   roll error rms {:.2f} deg, max {:.2f} deg at t = {:.2f} s over {} control cycles; {}\n",
               r.tracking.rms_deg, r.tracking.max_deg, r.tracking.max_at_s, r.tracking.samples,
               o.detected ? fmt::format("{} (damping ratio {:.3f}, {} cycles)", o.text, o.damping_ratio, o.cycles)
                          : std::string("no roll oscillation"));
  }
}

/// Each side of the CAN bridge: what it carried and what it rejected.
void print_can_health(std::ostream& out, const RunReport& r) {
  for (const auto& [name, h] : r.can_health) {
    fmt::print(
        out,
        "{:<10} {}: {} messages to CAN, {} to LCM; frames sent {}, received {}; rejected: unknown id {}, wrong "
        "length {}, bad checksum {}, stale counter {}, out of range {}; error frames {}; ENOBUFS {}, dropped {}\n",
        name, h.interface_name, h.messages_to_can, h.messages_to_lcm, h.frames_sent, h.frames_received,
        h.rejected_unknown_id, h.rejected_wrong_length, h.rejected_bad_checksum, h.rejected_stale_counter,
        h.rejected_out_of_range, h.error_frames, h.send_enobufs, h.send_dropped + h.receive_dropped);
    if (h.fd) {
      out << "           CAN FD: " << h.fd_frames_sent << " of the frames sent and " << h.fd_frames_received
          << " of those received were FD frames\n";
    }
    if (!h.candump_file.empty())
      out << "           candump log " << h.candump_file << " (" << h.candump_lines << " frames)\n";
  }
}

void print_faults(std::ostream& out, const RunReport& r) {
  // Faults by process and code, in order of first appearance: the first message of each and
  // how many followed (the JSON summary lists them all).
  out << "faults     " << r.faults.size() << "\n";
  std::vector<std::pair<std::string, int>> order;
  std::map<std::pair<std::string, int>, int> count;
  for (const auto& fr : r.faults) {
    if (count[{fr.process, fr.code}]++ == 0) order.emplace_back(fr.process, fr.code);
  }
  std::size_t shown = 0;
  for (const auto& key : order) {
    if (++shown > 12) {
      out << "           ... (" << order.size() - 12 << " more kinds; every fault is in the JSON summary)\n";
      break;
    }
    for (const auto& fr : r.faults) {
      if (fr.process != key.first || fr.code != key.second) continue;
      fmt::print(out, "           [{} {} t={:.3f} s] {}", fr.process, contract::fault_code_name(fr.code), fr.rig_time_s,
                 fr.message);
      if (count[key] > 1) out << " (" << count[key] << " in all)";
      out << "\n";
      break;
    }
  }
}

/// Each process with how it ended, and the hosts they ran on.
void print_processes_and_hosts(std::ostream& out, const RunReport& r) {
  out << "processes ";
  for (const auto& p : r.processes) out << " " << p.name << "(" << p.ended << ")";
  out << "\n";
  if (!r.hosts.empty()) {
    out << "hosts     ";
    for (std::size_t i = 0; i < r.hosts.size(); ++i) {
      const HostSummary& h = r.hosts[i];
      std::string about = h.launcher ? "launcher" : "";
      if (!h.address.empty()) about += (about.empty() ? "" : ", ") + h.address;
      if (!h.network_namespace.empty()) about += (about.empty() ? "" : ", ") + h.network_namespace;
      out << (i ? "; " : " ") << h.name << (about.empty() ? "" : " (" + about + ")") << ":";
      for (std::size_t k = 0; k < h.processes.size(); ++k) out << (k ? ", " : " ") << h.processes[k];
    }
    out << "\n";
  }
}

/// Real-time priority that could not be applied: one line, with what to do.
void print_priority(std::ostream& out, const RunReport& r) {
  std::string no_priority, why;
  for (const auto& fr : r.faults) {
    if (fr.code != fault_event_t::CODE_REALTIME_UNAVAILABLE) continue;
    if (no_priority.find(fr.process) == std::string::npos)
      no_priority += (no_priority.empty() ? "" : ", ") + fr.process;
    why = fr.message;
  }
  if (!no_priority.empty()) {
    out << "priority   run.realtime_priority NOT applied in " << no_priority << " (" << why
        << "). Run rig as root, or give the rig's executables CAP_SYS_NICE and CAP_IPC_LOCK "
           "(setcap cap_sys_nice,cap_ipc_lock+ep build/bin/nimble_*), or set run.realtime_priority: 0\n";
  }
}

}  // namespace

void write_report_text(std::ostream& out, const RunReport& r) {
  const double sim_s = r.sim_time_s, wall_s = r.wall_time_s;
  out << "\n== run summary: " << r.scenario << " ==\n";
  out << "clock      " << r.clock << ", seed " << r.seed << "\n";
  out << "transport  " << r.transport << (r.transport_detail.empty() ? "" : "  (" + r.transport_detail + ")") << "\n";
  out << "log        " << r.log_file;
  if (!r.log.file.empty()) {
    fmt::print(out, ": {} events, {:.3f} s simulated, {}{}", r.log.events, r.log.sim_time_s, human_bytes(r.log.bytes),
               r.log.failure.empty() ? "" : " (whole events kept before the failure)");
  }
  out << "\n";
  fmt::print(out, "time       simulated {:.3f} s, wall {:.3f} s ({:.2f}x real time)\n", sim_s, wall_s,
             wall_s > 0 ? sim_s / wall_s : 0.0);
  print_channels_and_timing(out, r);
  print_flight(out, r);
  print_estimator_and_tracking(out, r);
  print_can_health(out, r);
  print_faults(out, r);
  print_processes_and_hosts(out, r);
  if (r.verdict.timing.judged) out << "timing     " << r.verdict.timing.text << "\n";
  print_priority(out, r);
  for (const TapFigures& t : r.taps) {
    out << t.title << ":";
    for (std::size_t i = 0; i < t.values.size(); ++i) {
      out << (i ? ", " : " ") << t.values[i].first << " " << t.values[i].second;
    }
    if (!t.note.empty()) out << " (" << t.note << ")";
    out << "\n";
  }
  out << "controlled " << (r.verdict.controlled ? "yes" : "NO") << ", returned to hover "
      << (r.verdict.hover ? "yes" : "no") << "\n";
  out << "result     " << r.verdict.text << "\n";
}

namespace {

/// The run's roll tracking and its oscillation, if it had a controller.
void write_tracking_json(JsonWriter& w, const RunReport& r) {
  if (r.tracking.samples == 0) return;
  const TrackingSummary& t = r.tracking;
  const Oscillation& o = r.verdict.tracking.oscillation;
  w.key("tracking").begin_object();
  w.key("samples").value(static_cast<long long>(t.samples));
  w.key("rms_deg").value(t.rms_deg).key("max_deg").value(t.max_deg).key("max_at_s").value(t.max_at_s);
  w.key("lost").value(r.verdict.tracking.lost);
  w.key("oscillation").begin_object();
  w.key("detected").value(o.detected);
  w.key("kind").value(!o.detected ? "" : o.growing ? "growing" : "sustained");
  w.key("frequency_hz").value(o.frequency_hz).key("amplitude_deg").value(o.amplitude_deg);
  w.key("damping_ratio").value(o.damping_ratio).key("start_s").value(o.start_s).key("cycles").value(o.cycles);
  w.end_object();
  w.end_object();
}

/// Each side of the CAN bridge: what it carried and what it rejected.
void write_can_json(JsonWriter& w, const std::map<std::string, nimble::CanHealth>& can_health) {
  w.key("can").begin_object();
  for (const auto& [name, h] : can_health) {
    const auto n = [](int64_t v) { return static_cast<long long>(v); };
    w.key(name).begin_object();
    w.key("interface").value(h.interface_name);
    w.key("messages_to_can").value(n(h.messages_to_can)).key("messages_to_lcm").value(n(h.messages_to_lcm));
    w.key("frames_sent").value(n(h.frames_sent)).key("frames_received").value(n(h.frames_received));
    w.key("fd").value(h.fd != 0);
    w.key("fd_frames_sent").value(n(h.fd_frames_sent)).key("fd_frames_received").value(n(h.fd_frames_received));
    w.key("rejected_unknown_id").value(n(h.rejected_unknown_id));
    w.key("rejected_wrong_length").value(n(h.rejected_wrong_length));
    w.key("rejected_bad_checksum").value(n(h.rejected_bad_checksum));
    w.key("rejected_stale_counter").value(n(h.rejected_stale_counter));
    w.key("rejected_out_of_range").value(n(h.rejected_out_of_range));
    w.key("counter_gaps").value(n(h.counter_gaps)).key("saturated_values").value(n(h.saturated_values));
    w.key("error_frames").value(n(h.error_frames)).key("bus_state").value(static_cast<int>(h.bus_state));
    w.key("last_error").value(h.last_error);
    w.key("send_enobufs").value(n(h.send_enobufs)).key("send_retries").value(n(h.send_retries));
    w.key("send_dropped").value(n(h.send_dropped)).key("receive_dropped").value(n(h.receive_dropped));
    w.key("candump_file").value(h.candump_file).key("candump_lines").value(n(h.candump_lines));
    w.end_object();
  }
  w.end_object();
}

/// The flight's extremes, ranges, final state, vertical excursion and its trace where kept.
void write_flight_json(JsonWriter& w, const RunReport& r) {
  const FlightSummary& f = r.flight;
  w.key("max_abs")
      .begin_object()
      .key("p")
      .value(f.max_abs_p)
      .key("v")
      .value(f.max_abs_v)
      .key("phi")
      .value(f.max_abs_phi)
      .key("theta")
      .value(f.max_abs_theta)
      .key("psi")
      .value(f.max_abs_psi)
      .end_object();
  w.key("ranges").begin_object();
  w.key("p").value(f.max_p - f.min_p).key("v").value(f.max_v - f.min_v).key("phi").value(f.max_phi - f.min_phi);
  w.key("delta_f").value(f.max_df - f.min_df);
  w.end_object();
  w.key("final")
      .begin_object()
      .key("p")
      .value(f.final_p)
      .key("v")
      .value(f.final_v)
      .key("phi")
      .value(f.final_phi)
      .end_object();
  w.key("vertical").begin_object();
  w.key("height_min_m").value(f.min_height_m).key("height_max_m").value(f.max_height_m);
  w.key("height_final_m").value(f.final_height_m).key("max_abs_height_change_m").value(f.max_abs_height_change_m());
  w.key("w_min_mps").value(f.min_w).key("w_max_mps").value(f.max_w).key("w_initial_mps").value(f.initial_w);
  w.end_object();
  if (f.trace_dt_s > 0) {
    w.key("trace").begin_object().key("dt_s").value(f.trace_dt_s);
    const auto series = [&w](const char* name, const std::vector<double>& xs) {
      w.key(name).begin_array();
      for (const double x : xs) w.value(x);
      w.end_array();
    };
    series("p", f.trace_p);
    series("v", f.trace_v);
    series("phi", f.trace_phi);
    w.end_object();
  }
}

void write_estimator_json(JsonWriter& w, const RunReport& r) {
  const EstimatorSummary& est = r.estimator;
  if (est.samples > 0) {
    w.key("estimator").begin_object();
    w.key("samples").value(static_cast<long long>(est.samples));
    w.key("phi_rms_deg").value(est.phi_rms_deg).key("phi_max_deg").value(est.phi_max_deg);
    w.key("p_rms_radps").value(est.p_rms_radps).key("v_rms_mps").value(est.v_rms_mps);
    w.key("poses_accepted").value(static_cast<long long>(est.poses_accepted));
    w.key("poses_rejected").value(static_cast<long long>(est.poses_rejected));
    w.key("poses_missing").value(static_cast<long long>(est.poses_missing));
    w.key("poses_too_old").value(static_cast<long long>(est.poses_too_old));
    w.key("poses_too_new").value(static_cast<long long>(est.poses_too_new));
    w.key("velocity_windows_uncovered").value(static_cast<long long>(est.velocity_windows_uncovered));
    w.key("imu_rejected").value(static_cast<long long>(est.imu_rejected));
    w.key("imu_gaps").value(static_cast<long long>(est.imu_gaps));
    w.end_object();
  }
}

void write_channels_json(JsonWriter& w, const RunReport& r) {
  w.key("channels").begin_object();
  for (const auto& [name, c] : r.channels) {
    w.key(name).begin_object();
    w.key("count").value(static_cast<long long>(c.count));
    w.key("rate_hz").value(c.rate_hz);
    w.key("expected_hz").value(c.expected_hz);
    w.key("drops").value(static_cast<long long>(c.drops));
    w.key("late").value(static_cast<long long>(c.late));
    w.key("malformed").value(static_cast<long long>(c.malformed));
    w.key("rate_basis").value(c.wall_clock ? "wall" : "sim");
    w.end_object();
  }
  w.end_object();
}

/// Each process's loop timing, message latency and what it received.
void write_timing_json(JsonWriter& w, const RunReport& r) {
  w.key("timing").begin_object();
  for (const auto& [name, t] : r.timing) {
    w.key(name).begin_object();
    w.key("loop_rate_hz").value(t.loop_rate_hz);
    w.key("loop_count").value(static_cast<long long>(t.loop_count));
    w.key("overruns").value(static_cast<long long>(t.overruns));
    w.key("jitter_p50_us").value(t.jitter_p50_us);
    w.key("jitter_p99_us").value(t.jitter_p99_us);
    w.key("jitter_max_us").value(t.jitter_max_us);
    w.key("latency_count").value(static_cast<long long>(t.latency_count));
    w.key("latency_p50_us").value(t.latency_p50_us);
    w.key("latency_p99_us").value(t.latency_p99_us);
    w.key("latency_max_us").value(t.latency_max_us);
    w.key("received").begin_object();
    for (const auto& [channel, rc] : t.received) {
      w.key(channel).begin_object();
      w.key("count").value(static_cast<long long>(rc.count)).key("late").value(static_cast<long long>(rc.late));
      w.end_object();
    }
    w.end_object();
    w.end_object();
  }
  w.end_object();
}

/// Every fault, each process with how it ended, and the hosts they ran on.
void write_faults_processes_hosts_json(JsonWriter& w, const RunReport& r) {
  w.key("faults").begin_array();
  for (const auto& fr : r.faults) {
    w.begin_object();
    w.key("process").value(fr.process).key("severity").value(fr.severity).key("code").value(fr.code);
    w.key("channel").value(fr.channel).key("message").value(fr.message).key("rig_time_s").value(fr.rig_time_s);
    w.end_object();
  }
  w.end_array();
  w.key("processes").begin_object();
  for (const auto& p : r.processes) {
    w.key(p.name).begin_object();
    w.key("pid").value(p.pid);
    w.key("exit_code").value(p.exit_code);
    w.key("signal").value(p.signal);
    for (const HostSummary& h : r.hosts) {
      if (std::find(h.processes.begin(), h.processes.end(), p.name) != h.processes.end()) w.key("host").value(h.name);
    }
    w.end_object();
  }
  w.end_object();
  if (!r.hosts.empty()) {
    w.key("hosts").begin_object();
    for (const HostSummary& h : r.hosts) {
      w.key(h.name).begin_object();
      w.key("launcher").value(h.launcher);
      w.key("address").value(h.address);
      w.key("network_namespace").value(h.network_namespace);
      w.key("processes").begin_array();
      for (const auto& p : h.processes) w.value(p);
      w.end_array();
      w.end_object();
    }
    w.end_object();
  }
}

}  // namespace

std::string report_json(const RunReport& r) {
  JsonWriter w;
  w.begin_object();
  w.key("scenario").value(r.scenario);
  w.key("clock").value(r.clock);
  w.key("seed").value(static_cast<long long>(r.seed));
  w.key("config_digest").value(r.config_digest);
  w.key("lcm_url").value(r.transport);
  w.key("log").value(r.log_file);
  if (!r.log.file.empty()) {
    w.key("log_kept").begin_object();
    w.key("events").value(static_cast<long long>(r.log.events)).key("bytes").value(static_cast<long long>(r.log.bytes));
    w.key("sim_time_s").value(r.log.sim_time_s).key("failure").value(r.log.failure);
    w.end_object();
  }
  w.key("controlled").value(r.verdict.controlled);
  w.key("returned_to_hover").value(r.verdict.hover);
  w.key("exit_code").value(r.verdict.exit_code);
  w.key("result").value(r.verdict.text);
  if (r.verdict.timing.judged) {
    const TimingVerdict& tv = r.verdict.timing;
    w.key("realtime_health").begin_object();
    w.key("degraded").value(tv.degraded).key("worst_process").value(tv.worst);
    w.key("worst_fraction").value(tv.worst_fraction).key("text").value(tv.text);
    w.end_object();
  }
  w.key("sim_time_s").value(r.sim_time_s);
  w.key("wall_time_s").value(r.wall_time_s);
  w.key("speed_x_realtime").value(r.speed_x_realtime());
  write_flight_json(w, r);
  write_estimator_json(w, r);
  write_tracking_json(w, r);
  if (!r.can_health.empty()) write_can_json(w, r.can_health);
  write_channels_json(w, r);
  write_timing_json(w, r);
  write_faults_processes_hosts_json(w, r);
  for (const TapFigures& t : r.taps) {
    w.key(t.key).begin_object();
    for (const auto& v : t.values) w.key(v.first).value(v.second);
    if (!t.note.empty()) w.key("note").value(t.note);
    w.end_object();
  }
  w.end_object();
  return w.str();
}

int finish_report(const RunReport& report_in, const RunOptions& options) {
  RunReport report = report_in;
  // What the run writes after its log (--mcap's export, the --json file) is written before the
  // summary, so that the result line and the exit code say the same thing: an output that could
  // not be written turns an ok run into a failed one, named.
  const auto output_failed = [&report](const std::string& what) {
    if (report.verdict.exit_code == kRunOk) {
      report.verdict.exit_code = kRunFailed;
      report.verdict.text = "failed: " + what;
    } else {
      report.verdict.text += "; and " + what;
    }
  };
  if (options.after_log) {
    if (const std::string problem = options.after_log(report.log_file); !problem.empty()) output_failed(problem);
  }
  if (options.tap.state) options.tap.state("done", report.verdict.text, report.sim_time_s);
  if (options.tap.figures) report.taps.push_back(options.tap.figures());
  // --json -: stdout carries the JSON alone, the text summary goes to stderr.
  const bool json_stdout = options.json_file == "-";
  if (!json_stdout && !options.json_file.empty()) {
    try {
      write_file(options.json_file, report_json(report) + "\n");
    } catch (const OutputError& e) {
      std::cerr << "rig run: --json: " << e.what() << "\n";
      output_failed(std::string("--json: ") + e.what());
    }
  }
  if (options.print_summary) write_report_text(json_stdout ? std::cerr : std::cout, report);
  if (json_stdout) std::cout << report_json(report) << "\n";
  return report.verdict.exit_code;
}

}  // namespace nimble::launcher
