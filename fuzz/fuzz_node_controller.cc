// Fuzz target: the controller node's subscriptions, flying on the estimate (ESTIMATE) and on the
// truth (TRUTH), with the lockstep side's channels; see node_harness.h.

#include <memory>

#include "controller/controller_node.h"
#include "fuzz/node_harness.h"

namespace {

void build(nimble::fuzz::NodeRig& rig) {
  using nimble::fuzz::fuzz_scenario;
  const auto& on_estimate = fuzz_scenario("hover.yaml", {"run.controller_input=estimate"});
  const auto& on_truth = fuzz_scenario("hover.yaml", {"run.controller_input=truth"});
  rig.add(std::make_shared<nimble::ControllerNode>(
      on_estimate, nimble::transport::NodeOptions{"controller", on_estimate.file, "inprocess", &rig.hub}));
  rig.add(std::make_shared<nimble::ControllerNode>(
      on_truth, nimble::transport::NodeOptions{"controller", on_truth.file, "inprocess", &rig.hub}));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  nimble::fuzz::fuzz_nodes(data, size, build, false);
  return 0;
}
