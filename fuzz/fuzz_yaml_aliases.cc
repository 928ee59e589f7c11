// Fuzz target: the bounded YAML loader that every configuration file goes through
// (core/yaml_input.h, load_yaml_text: yaml-cpp's event stream read first, each anchor's size and
// depth counted as its aliases expand, then the tree). Text that loads must expand, walked with
// every alias followed, to at most kMaxYamlNodes nodes and kMaxYamlDepth levels (the walk stops
// one node past the bound: the count of the event stream and the tree then disagree, a finding),
// and the duplicate-key check that walks it too must end. Bad or bounded text is a ConfigError.
// The seeds are alias-heavy: alias bombs below and above the bound, deep nesting through aliases,
// anchors redefined, an alias of an unknown anchor, merge keys, several documents.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/config.h"
#include "core/yaml_input.h"
#include "fuzz/fuzz_support.h"

using nimble::fuzz::require;

namespace {

/// Walks `node` with every alias followed, counting nodes into `nodes` and returning its depth
/// (0 for a scalar); stops, returning, once `nodes` passes `budget`.
int walk(const YAML::Node& node, std::uint64_t budget, std::uint64_t* nodes) {
  if (++*nodes > budget) return 0;
  int depth = 0;
  if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end() && *nodes <= budget; ++it) {
      depth = std::max(depth, walk(it->first, budget, nodes));
      depth = std::max(depth, walk(it->second, budget, nodes));
    }
    return depth + 1;
  }
  if (node.IsSequence()) {
    for (auto it = node.begin(); it != node.end() && *nodes <= budget; ++it) {
      depth = std::max(depth, walk(*it, budget, nodes));
    }
    return depth + 1;
  }
  return 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string origin = "fuzz.yaml";
  YAML::Node root;
  try {
    root = nimble::load_yaml_text(text, origin);
  } catch (const nimble::ConfigError&) {
    return 0;  // the documented outcome of bad or bounded YAML
  }
  std::uint64_t nodes = 0;
  const int depth = walk(root, nimble::kMaxYamlNodes, &nodes);
  require(nodes <= nimble::kMaxYamlNodes, "YAML that loads expands past kMaxYamlNodes when walked");
  require(depth <= nimble::kMaxYamlDepth, "YAML that loads nests deeper than kMaxYamlDepth when walked");
  try {
    nimble::check_unique_keys(root, origin);
  } catch (const nimble::ConfigError&) {
    // a key given twice, or one that is no plain name: documented
  }
  return 0;
}
