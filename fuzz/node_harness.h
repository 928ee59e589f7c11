#pragma once
/// The harness of the node fuzz targets: raw bytes on the rig's channels, delivered to the
/// rig's node classes through an InprocessHub (the transport of `rig run --clock inprocess`).
///
/// An input is a sequence of records `selector (1 byte), length (2 bytes, little endian),
/// payload`. The selector picks a channel of contract::channel_table() (modulo the number of
/// channels, plus one more value for a raw CAN frame when the rig has a CAN bus); the payload is
/// published on it as it is and the hub is drained after each record. A record cut short by the
/// end of the input carries what is left.
///
/// The nodes are built once per `kInputsPerRig` inputs (building them loads the scenario's
/// models; a fresh rig per input would cost more than the fuzzing), joined as in-process
/// lockstep participants, and started by a RUN_CONTROL start of a short lockstep run, so that
/// the inputs also reach the handlers of a running node (RIG_CLOCK ticks run its tasks).
///
/// Properties checked for every record on a channel a node subscribes to: a payload that does
/// not decode exactly as the channel's type is counted as malformed by that node's Bus. Any exception that escapes a handler is a finding.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "can_bridge/inprocess_can_bus.h"
#include "scenario/scenario.h"
#include "transport/inprocess_hub.h"
#include "transport/node.h"

namespace nimble::fuzz {

/// The nodes under test, built on one hub (and CAN bus).
struct NodeRig {
  transport::InprocessHub hub;
  can::InprocessCanBus can_bus;
  std::vector<transport::ProcessNode*> nodes;    ///< every node's frame (for its Bus's counters)
  std::vector<std::shared_ptr<void>> owners;     ///< the node objects
  std::unique_ptr<can::FramePort> can_injector;  ///< the fuzzer's own endpoint on can_bus, if any

  /// Keeps `node` alive with the rig and watches its frame.
  template <typename Node>
  void add(std::shared_ptr<Node> node) {
    nodes.push_back(&node->node());
    owners.push_back(std::move(node));
  }
};

/// Builds the nodes of a target on `rig` (options: name, scenario file, "inprocess", &rig.hub).
using NodeFactory = std::function<void(NodeRig& rig)>;

/// Inputs handled by one NodeRig before it is built anew.
constexpr int kInputsPerRig = 256;

/// Loads rig_configs/<file> with `overrides` ("key.path=value"), once per target.
const Scenario& fuzz_scenario(const std::string& file, const std::vector<std::string>& overrides);

/// Runs one input against the nodes `factory` builds (see above). `with_can`: the rig has a CAN
/// bus and the extra selector injects a frame: payload byte 0 bit 0 = CAN FD, bytes 1..4 the
/// identifier (little endian, flags included), byte 5 the length, then the data.
void fuzz_nodes(const uint8_t* data, std::size_t size, const NodeFactory& factory, bool with_can);

}  // namespace nimble::fuzz
