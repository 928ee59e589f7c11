// Fuzz target: the plant node's subscriptions (ACTUATOR_CMD and the lockstep side's channels),
// over the LCM link and over the CAN link (ACTUATOR_CMD_CAN); see node_harness.h.

#include <memory>

#include "fuzz/node_harness.h"
#include "plant/plant_node.h"

namespace {

void build(nimble::fuzz::NodeRig& rig) {
  using nimble::fuzz::fuzz_scenario;
  const auto& lcm_link = fuzz_scenario("hover.yaml", {});
  const auto& can_link = fuzz_scenario("hover.yaml", {"actuator_link=can"});
  rig.add(std::make_shared<nimble::plant::PlantNode>(
      lcm_link, nimble::transport::NodeOptions{"plant", lcm_link.file, "inprocess", &rig.hub}));
  rig.add(std::make_shared<nimble::plant::PlantNode>(
      can_link, nimble::transport::NodeOptions{"plant", can_link.file, "inprocess", &rig.hub}));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  nimble::fuzz::fuzz_nodes(data, size, build, false);
  return 0;
}
