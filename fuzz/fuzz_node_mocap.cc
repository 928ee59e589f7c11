// Fuzz target: the motion-capture emulator node's subscriptions (TRUTH and the lockstep side's
// channels); see node_harness.h.

#include <memory>

#include "fuzz/node_harness.h"
#include "mocap/mocap_node.h"

namespace {

void build(nimble::fuzz::NodeRig& rig) {
  const auto& s = nimble::fuzz::fuzz_scenario("hover.yaml", {});
  rig.add(
      std::make_shared<nimble::MocapNode>(s, nimble::transport::NodeOptions{"mocap", s.file, "inprocess", &rig.hub}));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  nimble::fuzz::fuzz_nodes(data, size, build, false);
  return 0;
}
