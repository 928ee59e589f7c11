/// nimble_controller: the attitude controller process. Usage:
///   nimble_controller --scenario <resolved scenario.yaml> [--lcm-url URL] [--name controller]
/// Normally started by `rig run`; see controller_node.h for its channels.

#include <iostream>

#include "controller/controller_node.h"

int main(int argc, char** argv) {
  using namespace nimble;
  try {
    const transport::NodeOptions options = transport::parse_node_options(argc, argv, "controller");
    const Scenario scenario = load_scenario(options.scenario_file);
    transport::ProcessNode::install_signal_handlers();
    ControllerNode node(scenario, options);
    return node.run();
  } catch (const ConfigError& e) {
    std::cerr << "nimble_controller: config error: " << e.what() << "\n";
    return transport::kExitConfig;
  } catch (const std::exception& e) {
    std::cerr << "nimble_controller: error: " << e.what() << "\n";
    return transport::kExitConfig;
  }
}
