/// A live run from Python (nimble_rig.subscribe): the rig's channels received over LCM, as
/// lcm-spy receives them, through the rig's own transport (transport/bus.h) — Debian has no
/// Python bindings of LCM. nimble_rig/participant.py's decoder turns the bytes into messages.

#include <algorithm>
#include <chrono>
#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include "python/py_module.h"
#include "transport/bus.h"

namespace nimble::python {
namespace {

/// Messages of some channels received on an LCM URL, in the order they came.
class Subscription {
 public:
  /// @throws TransportError (RuntimeError) naming the URL if LCM does not start on it.
  Subscription(const std::vector<std::string>& channels, const std::string& url) : bus_(url) {
    const std::string pattern = channels_pattern(channels);
    bus_.subscribe_raw(pattern.empty() ? ".*" : pattern,
                       [this](const std::string& channel, const void* data, int size, int64_t) {
                         received_.emplace_back(channel, std::string(static_cast<const char*>(data), size));
                       });
  }

  /// The next message as (channel, bytes), waiting up to `timeout_s` [s] for it (the GIL released
  /// while it waits); None if none came by then.
  py::object next(double timeout_s) {
    if (received_.empty()) {
      py::gil_scoped_release free;
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
      while (received_.empty()) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) break;
        bus_.handle_timeout(static_cast<int>(std::min<long long>(left.count(), 100)));
      }
    }
    if (received_.empty()) return py::none();
    auto [channel, bytes] = std::move(received_.front());
    received_.pop_front();
    return py::make_tuple(channel, py::bytes(bytes));
  }

  const std::string& url() const { return bus_.url(); }

 private:
  transport::Bus bus_;
  std::deque<std::pair<std::string, std::string>> received_;
};

}  // namespace

void add_subscribe(py::module_& m) {
  py::class_<Subscription>(m, "_Subscription", "Messages of some channels received on an LCM URL (subscribe()).")
      .def(py::init<const std::vector<std::string>&, const std::string&>(), py::arg("channels"), py::arg("url"))
      .def("next", &Subscription::next, py::arg("timeout_s"),
           "The next message as (channel, bytes), waiting up to timeout_s [s]; None if none came.")
      .def_property_readonly("url", &Subscription::url, "the LCM URL it listens on");
}

}  // namespace nimble::python
