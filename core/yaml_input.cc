#include "core/yaml_input.h"

#include <algorithm>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <yaml-cpp/eventhandler.h>

#include "core/config.h"

namespace nimble {
namespace {

/// Counts a document's nodes and depth as its aliases expand, refusing past the bounds.
class ExpansionCounter : public YAML::EventHandler {
 public:
  explicit ExpansionCounter(const std::string& source) : source_(source) {}

  void OnDocumentStart(const YAML::Mark&) override {
    frames_.clear();
    anchors_.clear();
    frames_.push_back(Frame{0, 0, 0, YAML::Mark::null_mark()});
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { leaf(mark, anchor); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, const std::string&) override {
    leaf(mark, anchor);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto it = anchors_.find(anchor);
    if (it == anchors_.end()) {
      // The parser refuses an unknown anchor, so this one is still open: an alias inside the node
      // it names, which yaml-cpp builds as a node that contains itself (endless to walk).
      throw ConfigError(source_, "", "", "a YAML alias inside the node its anchor names (a cycle)",
                        mark.is_null() ? -1 : mark.line + 1);
    }
    add(mark, it->second);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(mark, anchor);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(mark, anchor);
  }
  void OnMapEnd() override { close(); }

 private:
  /// A node's size as expanded: nodes, and levels of collections (0 for a scalar).
  struct Size {
    std::uint64_t nodes;
    int depth;
  };
  /// An open collection: its anchor, its nodes so far (itself included) and its deepest child.
  struct Frame {
    YAML::anchor_t anchor;
    std::uint64_t nodes;
    int child_depth;
    YAML::Mark mark;
  };

  void leaf(const YAML::Mark& mark, YAML::anchor_t anchor) {
    if (anchor != 0) anchors_[anchor] = Size{1, 0};
    add(mark, Size{1, 0});
  }

  void open(const YAML::Mark& mark, YAML::anchor_t anchor) {
    check(mark, Size{1, 1});
    frames_.push_back(Frame{anchor, 1, 0, mark});
  }

  void close() {
    if (frames_.size() < 2) return;
    const Frame f = frames_.back();
    frames_.pop_back();
    const Size s{f.nodes, f.child_depth + 1};
    if (f.anchor != 0) anchors_[f.anchor] = s;
    add(f.mark, s, false);
  }

  /// Adds a finished node of size `s` to the collection that holds it.
  void add(const YAML::Mark& mark, const Size& s, bool checked = true) {
    if (checked) check(mark, s);
    Frame& parent = frames_.back();
    parent.nodes += s.nodes;
    parent.child_depth = std::max(parent.child_depth, s.depth);
  }

  /// Refuses a node of size `s` at the current position if the document would pass a bound.
  void check(const YAML::Mark& mark, const Size& s) {
    std::uint64_t nodes = 0;
    for (const Frame& f : frames_) nodes += f.nodes;
    // The open collections, each counted once already in `nodes`, hold the new node.
    const int depth = static_cast<int>(frames_.size()) - 1 + s.depth;
    const int line = mark.is_null() ? -1 : mark.line + 1;
    if (nodes + s.nodes > kMaxYamlNodes) {
      throw ConfigError(source_, "", "",
                        "YAML aliases expand to more than " + std::to_string(kMaxYamlNodes) +
                            " nodes (the bound of a configuration file); write the values out or use fewer aliases",
                        line);
    }
    if (depth > kMaxYamlDepth) {
      throw ConfigError(source_, "", "",
                        "YAML nests deeper than " + std::to_string(kMaxYamlDepth) +
                            " levels (the bound of a configuration file, aliases expanded)",
                        line);
    }
  }

  const std::string& source_;
  std::vector<Frame> frames_;
  std::unordered_map<YAML::anchor_t, Size> anchors_;
};

}  // namespace

void check_yaml_expansion(const std::string& text, const std::string& source) {
  std::istringstream in(text);
  try {
    YAML::Parser parser(in);
    ExpansionCounter counter(source);
    // The first document only: the one YAML::Load builds (and asking yaml-cpp 0.7 for the next
    // document after some malformed text returns true for ever).
    parser.HandleNextDocument(counter);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(source, "", "", "not valid YAML: " + e.msg, e.mark.line + 1);
  }
}

YAML::Node load_yaml_text(const std::string& text, const std::string& source) {
  check_yaml_expansion(text, source);
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(source, "", "", "not valid YAML: " + e.msg, e.mark.line + 1);
  }
}

YAML::Node load_yaml_file(const std::string& file, const std::string& referrer_key, InputKind kind) {
  std::string text;
  try {
    text = read_input_file(file, kind);
  } catch (const InputFileError& e) {
    throw ConfigError(file, referrer_key, "", e.problem());
  }
  return load_yaml_text(text, file);
}

}  // namespace nimble
