// The one number formatter and join of format.hpp.
#include "ukdyn/core/format.hpp"

#include <charconv>
#include <system_error>

namespace ukdyn {

std::string format_number(double v, int significant) {
  char buf[64];
  const std::to_chars_result r =
      significant > 0 ? std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general,
                                      significant > 40 ? 40 : significant)
                      : std::to_chars(buf, buf + sizeof buf, v);
  return r.ec == std::errc() ? std::string(buf, r.ptr) : std::string("?");
}

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += separator;
    out += item;
  }
  return out;
}

}  // namespace ukdyn
