// SPDX-License-Identifier: BSD-3-Clause
// The model file as YAML text, before its keys are read: what yaml-cpp's node tree hides or
// accepts silently is refused here, located (modelfile/reader.hpp):
//   - a key given twice in one mapping (yaml-cpp keeps both pairs and `node[key]` finds the
//     first, while iterating sees both: the copy that wins would depend on the section);
//   - more than one document (YAML::Load reads the first and ignores the rest);
//   - an alias used inside the node it names (*a inside &a: a node that contains itself);
//   - nesting deeper than yaml-cpp's reader allows (its message is "bad file"), or deeper than
//     the stack of the calling thread holds: yaml-cpp's parser recurses once per level (about
//     300 bytes a level, in this check and again in YAML::Load), so under `ulimit -s 64` its
//     own limit of 500 levels overflowed the stack. Each level's start compares the stack left
//     (the thread's stack bounds, pthread_getattr_np) with a reserve that the rest of the
//     reading needs, and refuses the file, located, when less is left.
// One pass over the parser's events: O(size of the text), aliases are not expanded. The same pass
// builds the node tree (what YAML::Load builds, marks included: TreeBuilder below), so the text
// is scanned once — yaml-cpp's scanner is about 1500 instructions a byte, and a model of 10⁵
// coordinates is 2 MB of YAML.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>
#include <yaml-cpp/yaml.h>

#include "modelfile/reader.hpp"
#include "modelfile/stack_floor.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::model_reader {
namespace {
struct NodeOfTree;  // a tag: the node tree's handle made by TreeBuilder (below)
}  // namespace
}  // namespace ukdyn::model_reader

// YAML::Node's constructor from a tree node is private; as_if is its friend, and this
// specialization for a type of ukdyn's own is how TreeBuilder makes the root's handle (as
// yaml-cpp's own NodeBuilder, which is not exported, does)
template <>
struct YAML::as_if<ukdyn::model_reader::NodeOfTree, void> {
  static Node make(detail::node& root, const detail::shared_memory_holder& memory) {
    return Node(root, memory);
  }
};

namespace ukdyn::model_reader {
namespace {

// The node tree of the first document from the parser's events: yaml-cpp's NodeBuilder (the one
// YAML::Load uses, src/nodebuilder.cpp of yaml-cpp 0.7) written again, step for step, so that
// the tree, its marks, tags and styles are those YAML::Load gives.
class TreeBuilder {
 public:
  TreeBuilder() : memory_(std::make_shared<YAML::detail::memory_holder>()) {
    anchors_.push_back(nullptr);  // anchors count from 1
  }

  YAML::Node root() const {
    if (root_ == nullptr) return YAML::Node();
    return YAML::as_if<NodeOfTree, void>::make(*root_, memory_);
  }

  void null(const YAML::Mark& mark, YAML::anchor_t anchor) {
    push(mark, anchor).set_null();
    pop();
  }
  void alias(YAML::anchor_t anchor) {
    push(*anchors_[anchor]);
    pop();
  }
  void scalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
              const std::string& value) {
    YAML::detail::node& node = push(mark, anchor);
    node.set_scalar(value);
    node.set_tag(tag);
    pop();
  }
  void sequence_start(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                      YAML::EmitterStyle::value style) {
    YAML::detail::node& node = push(mark, anchor);
    node.set_tag(tag);
    node.set_type(YAML::NodeType::Sequence);
    node.set_style(style);
  }
  void sequence_end() { pop(); }
  void map_start(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                 YAML::EmitterStyle::value style) {
    YAML::detail::node& node = push(mark, anchor);
    node.set_type(YAML::NodeType::Map);
    node.set_tag(tag);
    node.set_style(style);
    ++map_depth_;
  }
  void map_end() {
    --map_depth_;
    pop();
  }

 private:
  YAML::detail::node& push(const YAML::Mark& mark, YAML::anchor_t anchor) {
    YAML::detail::node& node = memory_->create_node();
    node.set_mark(mark);
    if (anchor != 0) anchors_.push_back(&node);  // anchors are numbered in order
    push(node);
    return node;
  }
  void push(YAML::detail::node& node) {
    const bool needs_key = !stack_.empty() && stack_.back()->type() == YAML::NodeType::Map &&
                           keys_.size() < map_depth_;
    stack_.push_back(&node);
    if (needs_key) keys_.emplace_back(&node, false);
  }
  void pop() {
    if (stack_.size() == 1) {
      root_ = stack_.front();
      stack_.pop_back();
      return;
    }
    YAML::detail::node& node = *stack_.back();
    stack_.pop_back();
    YAML::detail::node& collection = *stack_.back();
    if (collection.type() == YAML::NodeType::Sequence) {
      collection.push_back(node, memory_);
    } else if (collection.type() == YAML::NodeType::Map) {
      auto& [key, has_value] = keys_.back();
      if (has_value) {
        collection.insert(*key, node, memory_);
        keys_.pop_back();
      } else {
        has_value = true;
      }
    }
  }

  YAML::detail::shared_memory_holder memory_;
  YAML::detail::node* root_ = nullptr;
  std::vector<YAML::detail::node*> stack_, anchors_;
  std::vector<std::pair<YAML::detail::node*, bool>> keys_;  // a map's key, its value seen
  std::size_t map_depth_ = 0;
};

// a mapping or sequence being read
struct Open {
  bool map = false;
  YAML::anchor_t anchor = 0;
  bool expect_key = true;                  // a mapping: the next node is a key
  std::map<std::string, YAML::Mark> keys;  // a mapping: its scalar keys, where first seen
};

class StructureCheck final : public YAML::EventHandler {
 public:
  explicit StructureCheck(const std::string& file) : file_(file), floor_(detail::stack_floor()) {}

  // the first document's node tree (once the parser has gone through it)
  YAML::Node root() const { return tree_.root(); }

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1) {
      throw ModelError(file_, mark.line + 1, mark.column + 1,
                       "a second YAML document ('---'): a model file holds one model",
                       "put each model in its own file, or delete the '---' line and what "
                       "follows");
    }
  }
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    node(mark, nullptr);
    tree_.null(mark, anchor);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    for (const Open& o : open_) {
      if (o.anchor != 0 && o.anchor == anchor) {
        throw ModelError(file_, mark.line + 1, mark.column + 1,
                         "this alias refers to a node that contains it (a node cannot hold "
                         "itself)",
                         "write the value out, or refer to a node outside this one");
      }
    }
    node(mark, nullptr);
    tree_.alias(anchor);
  }
  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                const std::string& value) override {
    node(mark, &value);
    tree_.scalar(mark, tag, anchor, value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value style) override {
    node(mark, nullptr);
    check_stack(mark);
    open_.push_back(Open{.map = false, .anchor = anchor});
    tree_.sequence_start(mark, tag, anchor, style);
  }
  void OnSequenceEnd() override {
    open_.pop_back();
    tree_.sequence_end();
  }
  void OnMapStart(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value style) override {
    node(mark, nullptr);
    check_stack(mark);
    open_.push_back(Open{.map = true, .anchor = anchor});
    tree_.map_start(mark, tag, anchor, style);
  }
  void OnMapEnd() override {
    open_.pop_back();
    tree_.map_end();
  }

 private:
  // a collection starts at `mark`, one level deeper: refused when the stack left (the stack
  // grows down, towards floor_) is below the reserve
  void check_stack(const YAML::Mark& mark) const {
    const char here = 0;
    if (detail::stack_left(&here, floor_) > 0) return;
    throw ModelError(file_, mark.line + 1, mark.column + 1,
                     "the YAML nests too deep for this process's stack (" +
                         format_number(open_.size()) + " levels of brackets or indentation here)",
                     "a model file needs a few levels: check for unclosed or runaway brackets "
                     "(or raise the stack limit, ulimit -s)");
  }

  // a node starts at `mark`; `scalar`: its text when it is a scalar
  void node(const YAML::Mark& mark, const std::string* scalar) {
    if (open_.empty() || !open_.back().map) return;
    Open& m = open_.back();
    const bool key = m.expect_key;
    m.expect_key = !m.expect_key;
    if (!key || scalar == nullptr) return;
    const auto [first, inserted] = m.keys.emplace(*scalar, mark);
    if (!inserted) {
      throw ModelError(file_, mark.line + 1, mark.column + 1,
                       "the key '" + *scalar + "' is given twice in this mapping (first at line " +
                           format_number(first->second.line + 1) + ", column " +
                           format_number(first->second.column + 1) + ")",
                       "keep one of them: a model file never picks one copy silently");
    }
  }

  const std::string& file_;
  const char* floor_;  // the lowest stack address the nesting may reach (stack_floor)
  int documents_ = 0;
  std::vector<Open> open_;
  TreeBuilder tree_;  // of the first document (a second one is refused at its start)
};

}  // namespace

YAML::Node load_checked_yaml(const std::string& text, const std::string& file) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  StructureCheck check(file);
  try {
    while (parser.HandleNextDocument(check)) {
    }
    return check.root();
  } catch (const YAML::DeepRecursion& e) {
    throw ModelError(file, e.mark.line + 1, e.mark.column + 1,
                     "the YAML nests too deep (more than " + format_number(e.depth() - 1) +
                         " levels of brackets or indentation)",
                     "a model file needs a few levels: check for unclosed or runaway brackets");
  } catch (const YAML::ParserException& e) {
    std::string hint = "check the indentation, brackets and colons";
    throw ModelError(file, e.mark.line + 1, e.mark.column + 1, "YAML syntax: " + e.msg, hint);
  }
}

}  // namespace ukdyn::model_reader
