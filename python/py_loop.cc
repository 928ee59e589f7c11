/// loop of nimble_rig._rig: `rig loop`'s analysis of a scenario's roll loop (loop/loop_study.h),
/// its --json content with, per analysed loop, the frequency response the Bode and Nyquist plots
/// draw and the discrete loop itself (A, B, C, D, dt), so that other tools can check it.

#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <complex>
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

py::array_t<std::complex<double>> complex_of(const std::vector<std::complex<double>>& v) {
  py::array_t<std::complex<double>> a(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(std::complex<double>));
  return a;
}

py::dict loop(const py::object& scenario, const std::optional<std::string>& model,
              const std::optional<std::string>& gains, const py::dict& overrides, const std::optional<std::string>& on,
              const std::optional<std::string>& clock, const std::string& break_at, bool all_sets,
              const std::optional<std::string>& box, const std::optional<std::string>& design,
              const std::string& design_name) {
  loop::LoopRequest r;
  if (py::isinstance<Scenario>(scenario)) {
    const auto& s = scenario.cast<const Scenario&>();
    r.scenario_file = s.options.scenario_file;
    r.overrides = s.options.overrides;
  } else {
    r.scenario_file = path_text(scenario);
  }
  for (const Override& o : overrides_of(overrides)) r.overrides.push_back(o);
  r.model_file = model.value_or("");
  r.gains = gains.value_or("");
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
    entry["ratio"] = complex_of(f.ratio);
    entry["tracking"] = complex_of(f.tracking);
    py::dict d;
    d["A"] = matrix_of(broken[k].A);
    d["B"] = matrix_of(broken[k].B);
    d["C"] = matrix_of(broken[k].C);
    d["D"] = broken[k].D;
    d["dt"] = broken[k].dt_s;
    entry["discrete"] = d;
  }
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
        "(L = -G). gains: a set's name or 'KP,KD'.");
}

}  // namespace nimble::python
