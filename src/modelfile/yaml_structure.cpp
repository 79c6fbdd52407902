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
// One pass over the parser's events: O(size of the text), aliases are not expanded.
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

#include "modelfile/reader.hpp"
#include "modelfile/stack_floor.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::model_reader {
namespace {

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

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1) {
      throw ModelError(file_, mark.line + 1, mark.column + 1,
                       "a second YAML document ('---'): a model file holds one model",
                       "put each model in its own file, or delete the '---' line and what "
                       "follows");
    }
  }
  void OnDocumentEnd() override {}

  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { node(mark, nullptr); }
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
  }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& value) override {
    node(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    node(mark, nullptr);
    check_stack(mark);
    open_.push_back(Open{.map = false, .anchor = anchor});
  }
  void OnSequenceEnd() override { open_.pop_back(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    node(mark, nullptr);
    check_stack(mark);
    open_.push_back(Open{.map = true, .anchor = anchor});
  }
  void OnMapEnd() override { open_.pop_back(); }

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
};

}  // namespace

void check_yaml_structure(const std::string& text, const std::string& file) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  StructureCheck check(file);
  try {
    while (parser.HandleNextDocument(check)) {
    }
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
