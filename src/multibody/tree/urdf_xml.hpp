// SPDX-License-Identifier: BSD-3-Clause
// The XML of a URDF file, read by TinyXML (the parser under urdfdom 3; Debian's libtinyxml-dev):
// what TinyXML lets through refused, and the place (line:column) of the element that an error is
// about, for the messages of urdf.cpp.
#pragma once

#include <string>

namespace ukdyn::tree::detail {

/// A place in a URDF file: 1-based line and column (a column counts characters, a tab as one);
/// line 0 when unknown.
struct UrdfPlace {
  int line = 0;
  int column = 0;
};

/// An element of a URDF file: the `occurrence`-th (from 0) `<tag name="name">` child of
/// `<robot>` (`name` empty: the first `<tag>` whose name is missing or empty; `tag` "robot": the
/// root),
/// or, when `child` is not empty, that element's first `<child>` element (the element itself when
/// it has none). `tag` empty: no element.
struct UrdfElement {
  std::string tag, name, child;
  int occurrence = 0;
};

/// Refuses `text` (a URDF file's bytes) unless it is one XML document whose one root element is
/// `<robot>`: TinyXML's errors at its place (an element never closed at its own start tag), and
/// what TinyXML accepts silently — text or a second element after the root, a stray end tag, a
/// NUL byte. `who` starts the message ("ukdyn::tree::load_urdf: <path>: "). @throws
/// std::invalid_argument "<who at line:column>not a valid URDF: …". Cost: one parse, O(size).
void check_urdf_xml(const std::string& text, const std::string& who);

/// Where `element` is in `text` (a URDF that check_urdf_xml accepted); line 0 when not there.
/// For the error path only. Cost: one parse, O(size).
UrdfPlace find_urdf_element(const std::string& text, const UrdfElement& element);

/// The element that an error message is about, by the forms of urdfdom's messages ("Could not
/// parse inertial element for Link [l1]", "child link [c] of joint [j] not found", "joint 'j' is
/// not unique", …) and the tree's ("link 'l' (joint 'j'): damping must be >= 0", "joint 'j'
/// mimics 'r': …"): the child element that holds the faulty value when the message says which
/// (<inertial>, <mimic>, <limit>, <origin>, …); tag empty when it names none. Cost O(message).
UrdfElement element_of_message(const std::string& message);

/// `who` ("…: <path>: ") with `at` put before its last ": " ("…: <path>:12:3: "); `who`
/// unchanged when `at` is unknown.
std::string located(const std::string& who, UrdfPlace at);

}  // namespace ukdyn::tree::detail
