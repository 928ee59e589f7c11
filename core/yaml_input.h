#pragma once
/// YAML text and files read within bounds, before yaml-cpp's tree is used.
///
/// yaml-cpp parses an alias as a second reference to its anchor's node: parsing is cheap, but
/// everything that walks the tree (the duplicate-key check, `base:` merging, cloning, the
/// emitter) walks each alias again. Ten lines of anchors, each aliasing the one before ten
/// times, are 10^10 nodes to walk. Every YAML document the rig loads is therefore first read as
/// yaml-cpp's event stream, counting each anchor's size and depth as expanded, and refused above
/// kMaxYamlNodes nodes or kMaxYamlDepth levels, naming the file and the line where the bound was
/// passed; an alias inside the node its own anchor names (`&a [*a]`, which yaml-cpp builds as a
/// node containing itself, and which crashed every walk of it) is refused as a cycle. The bounds
/// are far above any configuration (the largest shipped file, the thesis campaign with its
/// anchors, expands to 847 nodes and 5 levels).

#include <cstdint>
#include <string>

#include <yaml-cpp/yaml.h>

#include "core/input_file.h"

namespace nimble {

/// The most nodes (scalars, sequences and mappings, keys included) a YAML document may expand to.
inline constexpr std::uint64_t kMaxYamlNodes = 100'000;
/// The deepest nesting of sequences and mappings a YAML document may expand to.
inline constexpr int kMaxYamlDepth = 64;

/// Refuses YAML `text` whose first document (the one yaml-cpp's Load builds) expands, aliases
/// included, to more than kMaxYamlNodes nodes or kMaxYamlDepth levels, or holds an alias inside
/// its own anchor's node. `source` names it in errors.
/// @throws ConfigError naming `source` and the line; "not valid YAML" for text that does not parse.
void check_yaml_expansion(const std::string& text, const std::string& source);

/// Parses the first document of `text` after check_yaml_expansion().
/// @throws ConfigError naming `source` (and the line) for bounded or invalid YAML.
YAML::Node load_yaml_text(const std::string& text, const std::string& source);

/// Reads `file` with read_input_file() (a regular file within the bound of `kind`) and parses it
/// with load_yaml_text(). `referrer_key`: the key that named the file (a `base:`), in errors.
/// @throws ConfigError naming the file ("file not found", "is not a regular file (a FIFO)", the
///         bound, a read error, invalid or bounded YAML).
YAML::Node load_yaml_file(const std::string& file, const std::string& referrer_key = "",
                          InputKind kind = InputKind::kConfig);

}  // namespace nimble
