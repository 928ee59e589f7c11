#include "launcher/run_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <ostream>

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <nimble/fault_event_t.hpp>

#include "contract/faults.h"
#include "core/output_file.h"

namespace nimble::launcher {

void describe_processes(RunReport& report, const Scenario& scenario, const RunMonitor& monitor) {
  for (ProcessOutcome& p : report.processes) {
    if (const RunMonitor::Heartbeat* hb = monitor.heartbeat(p.name)) p.heartbeats = hb->count;
    if (const auto it = scenario.participants.find(p.name); it != scenario.participants.end()) {
      p.python = "Python " + it->second.class_name + " of " +
                 std::filesystem::path(it->second.python_file).filename().string();
    }
  }
}

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
  for (const auto& p : r.processes) {
    out << " " << p.name << "(" << (p.python.empty() ? "" : p.python + "; ") << p.ended << ", " << p.heartbeats
        << (p.heartbeats == 1 ? " heartbeat)" : " heartbeats)");
  }
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
