/// nimble_plant: the plant process. Usage:
///   nimble_plant --scenario <resolved scenario.yaml> [--lcm-url URL] [--name plant]
/// Normally started by `rig run`; see plant_node.h for its channels.

#include "plant/plant_node.h"
#include "transport/process_main.h"

int main(int argc, char** argv) {
  return nimble::transport::process_main<nimble::plant::PlantNode>(argc, argv, "nimble_plant", "plant");
}
