/// nimble_plant: the plant process. Usage:
///   nimble_plant --scenario <resolved scenario.yaml> [--lcm-url URL] [--name plant]
/// Normally started by `rig run`; see plant_node.h for its channels.

#include <iostream>

#include "plant/plant_node.h"

int main(int argc, char** argv) {
  using namespace nimble;
  try {
    const transport::NodeOptions options = transport::parse_node_options(argc, argv, "plant");
    const Scenario scenario = load_scenario(options.scenario_file);
    transport::ProcessNode::install_signal_handlers();
    plant::PlantNode node(scenario, options);
    return node.run();
  } catch (const ConfigError& e) {
    std::cerr << "nimble_plant: config error: " << e.what() << "\n";
    return transport::kExitConfig;
  } catch (const std::exception& e) {
    std::cerr << "nimble_plant: error: " << e.what() << "\n";
    return transport::kExitConfig;
  }
}
