// Fuzz target: both sides of the CAN bridge node (can_flight and can_rig on one in-process CAN
// bus, classical and CAN FD): their LCM subscriptions (ACTUATOR_CMD, ACTUATOR_FB and the
// lockstep side's channels) and raw frames injected onto the bus; see node_harness.h.

#include <memory>

#include "can_bridge/bridge_config.h"
#include "can_bridge/bridge_node.h"
#include "fuzz/node_harness.h"

namespace {

void build(nimble::fuzz::NodeRig& rig) {
  using nimble::fuzz::fuzz_scenario;
  for (const char* fd : {"can_bridge.fd=false", "can_bridge.fd=true"}) {
    const auto& s = fuzz_scenario("hover.yaml", {"actuator_link=can", "can_bridge.candump_log=false", fd});
    for (const auto& name : {nimble::can::kFlightProcess, nimble::can::kRigProcess}) {
      rig.add(std::make_shared<nimble::can::CanBridgeNode>(
          s, nimble::transport::NodeOptions{name, s.file, "inprocess", &rig.hub}, &rig.can_bus));
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  nimble::fuzz::fuzz_nodes(data, size, build, true);
  return 0;
}
