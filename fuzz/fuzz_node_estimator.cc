// Fuzz target: the estimator node's subscriptions (IMU, MOCAP_POSE and the lockstep side's
// channels); see node_harness.h.

#include <memory>

#include "estimator/estimator_node.h"
#include "fuzz/node_harness.h"

namespace {

void build(nimble::fuzz::NodeRig& rig) {
  const auto& s = nimble::fuzz::fuzz_scenario("hover.yaml", {});
  rig.add(std::make_shared<nimble::EstimatorNode>(
      s, nimble::transport::NodeOptions{"estimator", s.file, "inprocess", &rig.hub}));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  nimble::fuzz::fuzz_nodes(data, size, build, false);
  return 0;
}
