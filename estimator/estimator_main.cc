/// nimble_estimator: the EKF process. Usage:
///   nimble_estimator --scenario <resolved scenario.yaml> [--lcm-url URL] [--name estimator]
/// Normally started by `rig run`; see estimator_node.h for its channels.

#include <iostream>

#include "estimator/estimator_node.h"

int main(int argc, char** argv) {
  using namespace nimble;
  try {
    const transport::NodeOptions options = transport::parse_node_options(argc, argv, "estimator");
    const Scenario scenario = load_scenario(options.scenario_file);
    transport::ProcessNode::install_signal_handlers();
    EstimatorNode node(scenario, options);
    return node.run();
  } catch (const ConfigError& e) {
    std::cerr << "nimble_estimator: config error: " << e.what() << "\n";
    return transport::kExitConfig;
  } catch (const std::exception& e) {
    std::cerr << "nimble_estimator: error: " << e.what() << "\n";
    return transport::kExitConfig;
  }
}
