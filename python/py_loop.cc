/// loop of nimble_rig._rig: `rig loop`'s analysis of a scenario's roll loop (loop/loop_study.h),
/// its --json content with, per analysed loop, the frequency response the Bode and Nyquist plots
/// draw and the discrete loop itself (A, B, C, D, dt), so that other tools can check it.

#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <complex>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "controller/roll_loop.h"
#include "core/constants.h"
#include "loop/loop_report.h"
#include "loop/loop_study.h"
#include "python/py_module.h"

namespace nimble::python {
namespace {

py::array_t<double> matrix_of(const Eigen::MatrixXd& m) {
  py::array_t<double> a({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto out = a.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) out(i, j) = m(i, j);
  }
  return a;
}

/// The closed-loop poles of an analysis as numpy wants them, into a loop's entry: the poles s
/// [1/s] a complex array (slowest first), their damping [-] and natural frequency [Hz] arrays in
/// the same order, and the dominant pair's pole complex beside its damping and frequency.
void set_poles(py::dict entry, const RollLoopAnalysis& a) {
  std::vector<std::complex<double>> s;
  Eigen::VectorXd zeta(static_cast<Eigen::Index>(a.poles.size())), fn(zeta.size());
  for (std::size_t i = 0; i < a.poles.size(); ++i) {
    s.push_back(a.poles[i].s);
    zeta(static_cast<Eigen::Index>(i)) = a.poles[i].damping;
    fn(static_cast<Eigen::Index>(i)) = a.poles[i].natural_hz;
  }
  entry["closed_loop_poles"] = complex_array_of(s);
  entry["closed_loop_damping"] = array_of(zeta);
  entry["closed_loop_natural_hz"] = array_of(fn);
  if (a.has_dominant_pair) {
    py::dict d;
    d["pole"] = a.dominant.s;
    d["damping"] = a.dominant.damping;
    d["natural_hz"] = a.dominant.natural_hz;
    entry["dominant_pair"] = d;
  }
}

/// The loop broken at its break as a discrete state space, for numpy and scipy: A, B, C, D (D a
/// 1 x 1 array like the others), dt [s], and the same as a scipy.signal.dlti and a python-control
/// StateSpace, each where its package can be imported.
py::dict discrete_of(const BrokenLoop& b) {
  py::dict d;
  d["A"] = matrix_of(b.A);
  d["B"] = matrix_of(b.B);
  d["C"] = matrix_of(b.C);
  d["D"] = matrix_of(Eigen::MatrixXd::Constant(1, 1, b.D));
  d["dt"] = b.dt_s;
  // Each where its package imports (scripts/setup.sh installs python3-scipy; Debian has no
  // python-control): a package that is not there leaves its entry out.
  try {
    d["dlti"] =
        py::module_::import("scipy.signal").attr("dlti")(d["A"], d["B"], d["C"], d["D"], py::arg("dt") = b.dt_s);
  } catch (const py::error_already_set& e) {
    if (!e.matches(PyExc_ImportError)) throw;
  }
  try {
    d["control"] = py::module_::import("control").attr("ss")(d["A"], d["B"], d["C"], d["D"], b.dt_s);
  } catch (const py::error_already_set& e) {
    if (!e.matches(PyExc_ImportError)) throw;
  }
  return d;
}

/// gains= as `rig loop --gains` takes it: a set's name or "KP,KD" as they are, a pair of numbers
/// (KP [1/rad], KD [s/rad]), or a dict with kp_per_rad and kd_per_radps (a loop entry's own keys).
/// @throws TypeError (py::type_error) for anything else.
std::string gains_text(const py::object& gains) {
  if (gains.is_none()) return "";
  if (py::isinstance<py::str>(gains)) return gains.cast<std::string>();
  double kp = 0.0, kd = 0.0;
  if (py::isinstance<py::dict>(gains)) {
    const auto d = gains.cast<py::dict>();
    if (!d.contains("kp_per_rad") || !d.contains("kd_per_radps") || d.size() != 2)
      throw py::type_error("gains: a dict holds kp_per_rad and kd_per_radps, nothing else");
    kp = d["kp_per_rad"].cast<double>();
    kd = d["kd_per_radps"].cast<double>();
  } else if (py::isinstance<py::sequence>(gains) && py::len(gains) == 2) {
    kp = gains.cast<py::sequence>()[0].cast<double>();
    kd = gains.cast<py::sequence>()[1].cast<double>();
  } else {
    throw py::type_error("gains: a set's name, 'KP,KD', (KP, KD) or {'kp_per_rad': KP, 'kd_per_radps': KD}");
  }
  char text[64];
  std::snprintf(text, sizeof text, "%.17g,%.17g", kp, kd);
  return text;
}

py::dict loop(const py::object& scenario, const py::object& model, const py::object& gains, const py::dict& overrides,
              const std::optional<std::string>& on, const std::optional<std::string>& clock,
              const std::string& break_at, bool all_sets, const std::optional<std::string>& box,
              const std::optional<std::string>& design, const std::string& design_name) {
  loop::LoopRequest r;
  if (py::isinstance<Scenario>(scenario)) {
    const auto& s = scenario.cast<const Scenario&>();
    r.scenario_file = s.options.scenario_file;
    r.overrides = s.options.overrides;
  } else {
    r.scenario_file = path_text(scenario);
  }
  for (const Override& o : overrides_of(overrides)) r.overrides.push_back(o);
  std::optional<ModelFile> model_file;
  if (!model.is_none()) r.model_file = model_file.emplace(model).path();
  r.gains = gains_text(gains);
  r.input = on.value_or("");
  r.clock = clock.value_or("");
  r.break_at = break_at;
  r.all_sets = all_sets;
  r.box_file = box.value_or("");
  r.design = design.value_or("");
  r.design_name = design_name;
  loop::LoopStudy study;
  std::vector<RollLoopResponse> responses;
  std::vector<BrokenLoop> broken;
  {
    py::gil_scoped_release free;
    study = loop::study_loop(r);
    for (const loop::LoopRow& row : study.rows) {
      responses.push_back(loop::row_response(row));
      broken.push_back(roll_broken_loop(row.lateral, row.config, row.where));
    }
  }
  py::dict out =
      json_value(loop::loop_json(study.setup, study.rows, study.worst, study.design ? &*study.design : nullptr));
  py::list loops = out["loops"];
  for (std::size_t k = 0; k < study.rows.size(); ++k) {
    py::dict entry = loops[k];
    const RollLoopResponse& f = responses[k];
    Eigen::VectorXd hz(static_cast<Eigen::Index>(f.omega_radps.size()));
    for (std::size_t i = 0; i < f.omega_radps.size(); ++i)
      hz(static_cast<Eigen::Index>(i)) = f.omega_radps[i] / (2 * kPi);
    entry["frequency_hz"] = array_of(hz);
    entry["ratio"] = complex_array_of(f.ratio);
    entry["tracking"] = complex_array_of(f.tracking);
    entry["discrete"] = discrete_of(broken[k]);
    set_poles(entry, study.rows[k].analysis);
  }
  if (study.design && study.design->design.feasible) set_poles(out["design"], study.design->design.analysis);
  out["ok"] = study.ok();
  return out;
}

}  // namespace

void add_loop(py::module_& m) {
  m.def("loop", &loop, py::arg("scenario"), py::kw_only(), py::arg("model") = py::none(), py::arg("gains") = py::none(),
        py::arg("overrides") = py::dict(), py::arg("on") = py::none(), py::arg("clock") = py::none(),
        py::arg("break_at") = "actuator", py::arg("all_sets") = false, py::arg("box") = py::none(),
        py::arg("design") = py::none(), py::arg("design_name") = "designed",
        "The roll loop of a scenario (a path or a Scenario) as the rig flies it, as `rig loop`: returns its --json "
        "content as a dict ('loops' first: per model, gain set and break its margins, sensitivity peak, "
        "bandwidth and poles; 'robustness' with all_sets; 'design' with design='phase_margin_deg=45,"
        "crossover_hz=2') and 'ok' (rig loop's exit code 0). Each loop also carries 'frequency_hz' with the "
        "return ratio 'ratio' (L, complex) and 'tracking' (phi/phi_ref) on the grid the Bode plot draws, and "
        "'discrete': the loop broken there as x[k+1] = A x + B w, y = C x + D w, dt [s], closed by w = y "
        "(L = -G), with 'dlti' (scipy.signal.dlti) and, where python-control imports, 'control' (its "
        "StateSpace). Poles are complex arrays: 'closed_loop_poles' s [1/s] (slowest first) with "
        "'closed_loop_damping' [-] and 'closed_loop_natural_hz' [Hz] in the same order, 'dominant_pair' "
        "{'pole', 'damping', 'natural_hz'}. gains: a set's name, 'KP,KD', (KP [1/rad], KD [s/rad]) or "
        "{'kp_per_rad': KP, 'kd_per_radps': KD}.");
}

}  // namespace nimble::python
