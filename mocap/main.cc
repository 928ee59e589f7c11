/// nimble_mocap: the motion-capture emulator process. Usage:
///   nimble_mocap --scenario <resolved scenario.yaml> [--lcm-url URL] [--name mocap]
/// Normally started by `rig run`; see mocap_node.h for its channels.

#include <iostream>

#include "mocap/mocap_node.h"

int main(int argc, char** argv) {
  using namespace nimble;
  try {
    const transport::NodeOptions options = transport::parse_node_options(argc, argv, "mocap");
    const Scenario scenario = load_scenario(options.scenario_file);
    transport::ProcessNode::install_signal_handlers();
    MocapNode node(scenario, options);
    return node.run();
  } catch (const ConfigError& e) {
    std::cerr << "nimble_mocap: config error: " << e.what() << "\n";
    return transport::kExitConfig;
  } catch (const std::exception& e) {
    std::cerr << "nimble_mocap: error: " << e.what() << "\n";
    return transport::kExitConfig;
  }
}
