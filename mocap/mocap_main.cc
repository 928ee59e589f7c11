/// nimble_mocap: the motion-capture emulator process. Usage:
///   nimble_mocap --scenario <resolved scenario.yaml> [--lcm-url URL] [--name mocap]
/// Normally started by `rig run`; see mocap_node.h for its channels.

#include "mocap/mocap_node.h"
#include "transport/process_main.h"

int main(int argc, char** argv) {
  return nimble::transport::process_main<nimble::MocapNode>(argc, argv, "nimble_mocap", "mocap");
}
