// SPDX-License-Identifier: BSD-3-Clause
// The XML of a URDF file through TinyXML 2.6 (urdfdom 3 parses with it; Debian's libtinyxml-dev,
// a dependency of liburdfdom-dev): a parse before urdfdom's that refuses what TinyXML lets
// through, and the places of elements for the messages of urdf.cpp (urdf_xml.hpp).
#include "multibody/tree/urdf_xml.hpp"

#include <cctype>
#include <cstdio>
#include <regex>
#include <stdexcept>
#include <string>
#include <tuple>

#include <tinyxml.h>

namespace ukdyn::tree::detail {

namespace {

UrdfPlace xml_place(const TiXmlBase& node) { return {node.Row(), node.Column()}; }

std::string place_text(UrdfPlace at) {
  return std::to_string(at.line) + ":" + std::to_string(at.column);
}

// walks `text` as TinyXML counts places: "\n", "\r\n" and a lone "\r" end a line; a column is
// one character (UTF-8's continuation bytes and a leading byte-order mark are not counted); `stop`
// is called at each character's first byte with its offset and place and ends the walk by
// returning true. Returns the place just past the text when never stopped.
template <class Stop>
UrdfPlace walk_places(const std::string& text, Stop stop) {
  UrdfPlace at{1, 1};
  std::size_t k = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  for (; k < text.size(); ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if ((c & 0xC0) == 0x80) continue;  // inside a UTF-8 character
    if (stop(k, at)) return at;
    if (c == '\n' || c == '\r') {
      if (c == '\r' && k + 1 < text.size() && text[k + 1] == '\n') ++k;
      ++at.line;
      at.column = 1;
    } else {
      ++at.column;
    }
  }
  return at;
}

// the place of byte `offset` of `text`
UrdfPlace place_of_offset(const std::string& text, std::size_t offset) {
  return walk_places(text, [&](std::size_t k, UrdfPlace) { return k >= offset; });
}

// the byte offset of place `at` in `text` (text.size() when past its end)
std::size_t offset_of_place(const std::string& text, UrdfPlace at) {
  std::size_t offset = text.size();
  walk_places(text, [&](std::size_t k, UrdfPlace p) {
    if (p.line < at.line || (p.line == at.line && p.column < at.column)) return false;
    offset = k;
    return true;
  });
  return offset;
}

// up to 24 bytes of `text` from `offset`, to the end of the line, quoted; bytes that are not
// printable ASCII as \xNN (a binary file's garbage stays readable)
std::string quote_at(const std::string& text, std::size_t offset) {
  std::string out = "'";
  for (std::size_t k = offset; k < text.size() && k < offset + 24; ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c == '\n' || c == '\r') break;
    if (c >= 0x20 && c < 0x7F) {
      out += char(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02X", unsigned(c));
      out += hex;
    }
  }
  return out + "'";
}

// "<link name="a">", or "<visual>" for an element without a name
std::string element_text(const TiXmlElement& e) {
  const char* name = e.Attribute("name");
  return "<" + e.ValueStr() + (name ? " name=\"" + std::string(name) + "\"" : "") + ">";
}

// the last child element of `node`, or null
const TiXmlElement* last_element(const TiXmlNode& node) {
  for (const TiXmlNode* c = node.LastChild(); c; c = c->PreviousSibling()) {
    if (const TiXmlElement* e = c->ToElement()) return e;
  }
  return nullptr;
}

// whether element `e` was closed in `text` before byte `limit`: its start tag ends "/>", or its
// end tag "</tag>" follows (URDF nests no element in one of its own name)
bool closed_before(const std::string& text, const TiXmlElement& e, std::size_t limit) {
  std::size_t p = offset_of_place(text, xml_place(e));
  char quote = 0;
  for (; p < limit; ++p) {
    const char c = text[p];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '>') {
      break;
    }
  }
  if (p >= limit) return false;
  if (text[p - 1] == '/') return true;
  const std::string end_tag = "</" + e.ValueStr();
  for (std::size_t k = text.find(end_tag, p); k < limit; k = text.find(end_tag, k + 1)) {
    const std::size_t after = k + end_tag.size();
    if (after < text.size() &&
        (text[after] == '>' || std::isspace(static_cast<unsigned char>(text[after])))) {
      return true;
    }
  }
  return false;
}

[[noreturn]] void refuse_xml(const std::string& who, UrdfPlace at, const std::string& what) {
  throw std::invalid_argument(located(who, at) + "not a valid URDF: " + what);
}

// TinyXML's "Error reading end tag." (an end tag that is not the open element's, or the file
// ending inside an element): the element never closed is the innermost one open there — on the
// chain of last child elements, whose open ones come first (TinyXML links each element into its
// parent before reading its content)
// (`stop`: where TinyXML stopped, the end of the file when it does not say)
[[noreturn]] void refuse_unclosed(const std::string& text, const TiXmlDocument& doc,
                                  const std::string& who, UrdfPlace stop) {
  const std::size_t limit = offset_of_place(text, stop);
  const TiXmlElement* open = nullptr;
  for (const TiXmlElement* e = last_element(doc); e; e = last_element(*e)) {
    if (!closed_before(text, *e, limit)) open = e;
  }
  if (!open) {
    refuse_xml(who, stop, "the XML parser (TinyXML): \"" + std::string(doc.ErrorDesc()) + "\"");
  }
  // what comes before its end tag: another end tag (TinyXML may stop inside it, after "</li" of
  // "</link>" for <li>), or the end of the file
  std::string first = "the end of the file";
  const std::size_t tag = text.rfind("</", limit);
  if (tag != std::string::npos && text.find_first_of(">\n", tag) >= limit) {
    const std::size_t close = text.find('>', tag);
    first = (close == std::string::npos ? quote_at(text, tag) : text.substr(tag, close + 1 - tag)) +
            " at " + place_text(place_of_offset(text, tag));
  } else if (limit < text.size()) {
    first = quote_at(text, limit) + " at " + place_text(stop);
  }
  refuse_xml(
      who, xml_place(*open),
      element_text(*open) + " is not closed (no </" + open->ValueStr() + "> before " + first + ")");
}

}  // namespace

std::string located(const std::string& who, UrdfPlace at) {
  if (at.line <= 0 || who.size() < 2 || who.compare(who.size() - 2, 2, ": ") != 0) return who;
  return who.substr(0, who.size() - 2) + ":" + place_text(at) + ": ";
}

void check_urdf_xml(const std::string& text, const std::string& who) {
  const std::string kForm = "a URDF is <robot name=\"…\"> … </robot>";
  // a NUL byte: TinyXML reads a C string and would stop there without a word
  if (const std::size_t z = text.find('\0'); z != std::string::npos) {
    refuse_xml(who, place_of_offset(text, z), "the file holds a NUL byte (binary data, not XML)");
  }
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) refuse_xml(who, {1, 1}, "the file is empty (" + kForm + ")");
  TiXmlDocument doc;
  doc.SetTabSize(1);  // a tab is one column
  // (read as UTF-8 whatever the declaration says: a column is a character, as walk_places counts)
  const char* end = doc.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (doc.Error()) {
    if (doc.ErrorId() == TiXmlBase::TIXML_ERROR_DOCUMENT_EMPTY) {
      // (TinyXML found no markup at all)
      refuse_xml(
          who, place_of_offset(text, first),
          "no XML element: the file begins with " + quote_at(text, first) + " (" + kForm + ")");
    }
    const UrdfPlace at{doc.ErrorRow(), doc.ErrorCol()};
    if (at.line > 0 && doc.ErrorId() == TiXmlBase::TIXML_ERROR_READING_END_TAG) {
      refuse_unclosed(text, doc, who, at);
    }
    if (at.line <= 0) {
      // TinyXML gives no place when a comment or a CDATA section runs to the end of the file
      for (const auto& [open, close, what] :
           {std::tuple<std::string, std::string, std::string>{"<!--", "-->", "a comment"},
            {"<![CDATA[", "]]>", "a CDATA section"}}) {
        for (std::size_t k = text.find(open); k != std::string::npos;) {
          const std::size_t end_at = text.find(close, k + open.size());
          if (end_at == std::string::npos) {
            refuse_xml(who, place_of_offset(text, k),
                       what + " " + open + " is not closed (no " + close + " before the end of " +
                           "the file)");
          }
          k = text.find(open, end_at + close.size());
        }
      }
      refuse_unclosed(text, doc, who, place_of_offset(text, text.size()));
    }
    // TinyXML's own words, and what stands there
    refuse_xml(who, at,
               "the XML parser (TinyXML): \"" + std::string(doc.ErrorDesc()) + "\" at " +
                   quote_at(text, offset_of_place(text, at)));
  }
  // the document's nodes: one root element, besides the declaration, comments and a DOCTYPE
  const TiXmlElement* root = nullptr;
  for (const TiXmlNode* n = doc.FirstChild(); n; n = n->NextSibling()) {
    if (const TiXmlElement* e = n->ToElement()) {
      if (root) {
        refuse_xml(who, xml_place(*e),
                   "a second root element " + element_text(*e) + " after " + element_text(*root) +
                       " at " + place_text(xml_place(*root)) + " (a URDF file holds one <robot>)");
      }
      root = e;
    } else if (n->ToUnknown() && n->ValueStr().rfind("!DOCTYPE", 0) != 0) {
      const std::string v = n->ValueStr();
      refuse_xml(who, xml_place(*n),
                 v.rfind('/', 0) == 0 ? "an end tag <" + v + "> with no element open"
                                      : "markup <" + v + "> that is not XML");
    }
  }
  // text TinyXML could not read as a node: it stopped there and dropped the rest
  if (end && *end) {
    const std::size_t at = std::size_t(end - text.c_str());
    refuse_xml(who, place_of_offset(text, at),
               quote_at(text, at) +
                   (root ? " after the root element " + element_text(*root) + " at " +
                               place_text(xml_place(*root)) + " (only comments may follow it)"
                         : " where an element should begin (" + kForm + ")"));
  }
  if (!root) refuse_xml(who, place_of_offset(text, first), "no root element (" + kForm + ")");
  if (root->ValueStr() != "robot") {
    refuse_xml(who, xml_place(*root),
               "the root element is " + element_text(*root) + ", not <robot>");
  }
}

UrdfPlace find_urdf_element(const std::string& text, const UrdfElement& element) {
  if (element.tag.empty()) return {};
  TiXmlDocument doc;
  doc.SetTabSize(1);
  doc.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (!robot) return {};
  if (element.tag == "robot") return xml_place(*robot);
  int seen = 0;
  for (const TiXmlElement* e = robot->FirstChildElement(element.tag.c_str()); e;
       e = e->NextSiblingElement(element.tag.c_str())) {
    const char* name = e->Attribute("name");
    const bool match = element.name.empty() ? !name || !*name : name && element.name == name;
    if (!match || seen++ < element.occurrence) continue;
    if (!element.child.empty()) {
      if (const TiXmlElement* c = e->FirstChildElement(element.child.c_str())) return xml_place(*c);
    }
    return xml_place(*e);
  }
  return {};
}

UrdfElement element_of_message(const std::string& message) {
  // the forms, most specific first (urdfdom logs several messages for one fault, the element's
  // own first: "Inertial: mass [heavy] is not a float; Could not parse inertial element for Link
  // [l1]; link xml is not initialized correctly"); names in [..] are urdfdom's, in '..' the tree's
  static const std::regex child_of(
      R"(Could not parse (\w+) element for (Link|joint)\s+\[([^\]]*)\])");
  static const std::regex malformed(
      R"(Malformed (parent origin|axis) element for joint \[([^\]]*)\])");
  static const std::regex missing_link(R"((child|parent) link \[[\s\S]*?\] of joint \[([^\]]*)\])");
  static const std::regex not_unique(R"((link|joint|material) '([^']*)' is not unique)");
  static const std::regex two_roots(R"(Two root links found: \[[^\]]*\] and \[([^\]]*)\])");
  static const std::regex unnamed(R"((unnamed joint found)|(No name given for the link))");
  static const std::regex of_robot(
      R"(No name given for the robot|'version'|No link elements found|No root link found)");
  static const std::regex mimic(R"(joint '([^']*)'( mimics '[^']*')?: (a cycle of mimics)?)");
  static const std::regex floating(R"(joint '([^']*)': a floating joint('s origin| must attach))");
  static const std::regex link_joint(
      R"(link '([^']*)' \(joint '([^']*)'\): (the joint axis|the joint origin|friction|damping|mass|the inerti)?)");
  static const std::regex urdfdom_named(R"((Link|Joint|link|joint)\s*\[([^\]]*)\])");
  static const std::regex tree_named(R"((link|joint) '([^']*)')");
  std::smatch m;
  const auto lower = [](std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  if (std::regex_search(message, m, unnamed)) return {m[1].matched ? "joint" : "link", "", ""};
  if (std::regex_search(message, m, child_of)) {
    // <joint_dynamics> is urdfdom's name for the <dynamics> element
    return {lower(m[2]), m[3], m[1] == "joint_dynamics" ? "dynamics" : m[1].str()};
  }
  if (std::regex_search(message, m, malformed)) {
    return {"joint", m[2], m[1] == "axis" ? "axis" : "origin"};
  }
  if (std::regex_search(message, m, missing_link)) return {"joint", m[2], m[1]};
  if (std::regex_search(message, m, not_unique)) return {m[1], m[2], "", 1};
  if (std::regex_search(message, m, two_roots)) return {"link", m[1], ""};
  if (std::regex_search(message, m, of_robot)) return {"robot", "", ""};
  // the tree's: a mimic at its <mimic>, a joint's values at the element that holds them
  if (std::regex_search(message, m, mimic) && (m[2].matched || m[3].matched)) {
    return {"joint", m[1], "mimic"};
  }
  if (std::regex_search(message, m, floating)) {
    return {"joint", m[1], m[2] == "'s origin" ? "origin" : "parent"};
  }
  if (std::regex_search(message, m, link_joint)) {
    const std::string what = m[3];
    if (what == "the joint axis") return {"joint", m[2], "axis"};
    if (what == "the joint origin") return {"joint", m[2], "origin"};
    if (what == "friction" || what == "damping") return {"joint", m[2], "dynamics"};
    if (!what.empty()) return {"link", m[1], "inertial"};
    return {"link", m[1], ""};
  }
  if (std::regex_search(message, m, urdfdom_named)) return {lower(m[1]), m[2], ""};
  if (std::regex_search(message, m, tree_named)) return {m[1], m[2], ""};
  return {};
}

}  // namespace ukdyn::tree::detail
