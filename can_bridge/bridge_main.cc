/// nimble_can_bridge: one side of the CAN actuator link. Usage:
///   nimble_can_bridge --name can_flight|can_rig --scenario <resolved scenario.yaml> [--lcm-url URL]
/// Started by `rig run` when the scenario says `actuator_link: can`; see bridge_node.h.

#include "can_bridge/bridge_node.h"
#include "transport/process_main.h"

int main(int argc, char** argv) {
  return nimble::transport::process_main<nimble::can::CanBridgeNode>(argc, argv, "nimble_can_bridge",
                                                                     nimble::can::kRigProcess.c_str());
}
