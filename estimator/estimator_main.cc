/// nimble_estimator: the EKF process. Usage:
///   nimble_estimator --scenario <resolved scenario.yaml> [--lcm-url URL] [--name estimator]
/// Normally started by `rig run`; see estimator_node.h for its channels.

#include "estimator/estimator_node.h"
#include "transport/process_main.h"

int main(int argc, char** argv) {
  return nimble::transport::process_main<nimble::EstimatorNode>(argc, argv, "nimble_estimator", "estimator");
}
