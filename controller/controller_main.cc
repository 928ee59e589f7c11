/// nimble_controller: the attitude controller process. Usage:
///   nimble_controller --scenario <resolved scenario.yaml> [--lcm-url URL] [--name controller]
/// Normally started by `rig run`; see controller_node.h for its channels.

#include "controller/controller_node.h"
#include "transport/process_main.h"

int main(int argc, char** argv) {
  return nimble::transport::process_main<nimble::ControllerNode>(argc, argv, "nimble_controller", "controller");
}
