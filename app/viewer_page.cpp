// SPDX-License-Identifier: BSD-3-Clause
// The viewer page's text (app/viewer_page.hpp): the trajectory's rows shown, the data as JSON
// in Python's form, the template filled — python/ukdyn/viewer.py's read_csv, _json_for_html
// and build_page, rule for rule.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>

#include "viewer_page.hpp"

namespace ukdyn::cli {
namespace {

using json = nlohmann::ordered_json;

// The fields of a CSV header line (RFC 4180: a quoted field may hold commas and doubled quotes).
std::vector<std::string> header_fields(std::string_view line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else if (c != '\r' && c != '\n') {
      out.back() += c;
    }
  }
  return out;
}

bool blank(const std::string& line) {
  return line.find_first_not_of(" \t\r\n\f\v") == std::string::npos;
}

// A field as Python's float() reads it (surrounding blanks allowed; nan, inf, -inf), or an
// error naming the file and the line.
double number_at(std::string_view field, const std::filesystem::path& csv, long line) {
  const std::string text(field);
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  const bool blanks_only =
      end != begin && std::string_view(end).find_first_not_of(" \t\r\n") == std::string_view::npos;
  if (!blanks_only) {
    throw std::runtime_error(csv.string() + ":" + std::to_string(line) + ": '" + text +
                             "' is not a number");
  }
  return v;
}

// The numbers of a data row, one per column of the header.
std::vector<double> row_numbers(const std::string& row, std::size_t columns,
                                const std::filesystem::path& csv, long line) {
  std::vector<double> out;
  out.reserve(columns);
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = row.find(',', start);
    out.push_back(number_at(std::string_view(row).substr(start, comma - start), csv, line));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (out.size() != columns) {
    throw std::runtime_error(csv.string() + ":" + std::to_string(line) + ": " +
                             std::to_string(out.size()) + " fields, where the header has " +
                             std::to_string(columns));
  }
  return out;
}

std::ifstream open_csv(const std::filesystem::path& csv) {
  std::ifstream in(csv, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read '" + csv.string() + "'");
  return in;
}

// x as Python's repr(): the shortest digits that read back as x, fixed from 1e-4 to below
// 1e16 (with ".0" when whole), else d.ddde±XX
std::string python_float(double x) {
  if (!std::isfinite(x)) throw std::invalid_argument("python_json: a number that is not finite");
  char text[64];
  auto r = std::to_chars(text, text + sizeof text, x, std::chars_format::scientific);
  std::string s(text, r.ptr);
  const int exponent = std::atoi(s.c_str() + s.find('e') + 1);
  if (exponent < -4 || exponent >= 16) return s;
  r = std::to_chars(text, text + sizeof text, x, std::chars_format::fixed);
  s.assign(text, r.ptr);
  if (s.find('.') == std::string::npos) s += ".0";
  return s;
}

void write_python_json(const json& j, std::string& out) {
  switch (j.type()) {
    case json::value_t::null:
      out += "null";
      return;
    case json::value_t::boolean:
      out += j.get<bool>() ? "true" : "false";
      return;
    case json::value_t::number_integer:
      out += std::to_string(j.get<std::int64_t>());
      return;
    case json::value_t::number_unsigned:
      out += std::to_string(j.get<std::uint64_t>());
      return;
    case json::value_t::number_float:
      out += python_float(j.get<double>());
      return;
    case json::value_t::string:
      // (nlohmann's escapes are json.dumps's with ensure_ascii: \" \\ \b \f \n \r \t, \u00XX
      // for other controls and DEL, \uXXXX and surrogate pairs beyond ASCII, lower-case hex)
      out += j.dump(-1, ' ', true, json::error_handler_t::replace);
      return;
    case json::value_t::array: {
      out += '[';
      bool first = true;
      for (const json& item : j) {
        if (!first) out += ',';
        first = false;
        write_python_json(item, out);
      }
      out += ']';
      return;
    }
    case json::value_t::object: {
      out += '{';
      bool first = true;
      for (const auto& [key, value] : j.items()) {
        if (!first) out += ',';
        first = false;
        out += json(key).dump(-1, ' ', true, json::error_handler_t::replace);
        out += ':';
        write_python_json(value, out);
      }
      out += '}';
      return;
    }
    default:
      throw std::invalid_argument("python_json: a value JSON cannot hold");
  }
}

std::string replace_all(std::string_view text, std::string_view from, std::string_view to) {
  std::string out;
  out.reserve(text.size());
  std::size_t start = 0;
  for (std::size_t at = text.find(from); at != std::string_view::npos;
       at = text.find(from, start)) {
    out.append(text.substr(start, at - start)).append(to);
    start = at + from.size();
  }
  out.append(text.substr(start));
  return out;
}

std::string html_escape(std::string_view text) {
  std::string out;
  for (const char c : text) {
    if (c == '&') {
      out += "&amp;";
    } else if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

ViewerColumns read_viewer_csv(const std::filesystem::path& csv, const ViewerOptions& options,
                              const std::vector<std::string>& watch,
                              std::map<std::string, double>& first_nonfinite) {
  ViewerColumns out;
  // pass 1: the number of rows, the first and the last time (and where watched columns fail)
  std::size_t n = 0;
  double t0 = 0.0, t1 = 0.0;
  {
    std::ifstream in = open_csv(csv);
    std::string line;
    if (!std::getline(in, line)) throw std::runtime_error("'" + csv.string() + "' is empty");
    out.names = header_fields(line);
    std::vector<std::pair<std::size_t, std::string>> watched;
    for (const std::string& c : watch) {
      for (std::size_t k = 0; k < out.names.size(); ++k) {
        if (out.names[k] == c) {
          watched.emplace_back(k, c);
          break;
        }
      }
    }
    for (long number = 2; std::getline(in, line); ++number) {
      if (blank(line)) continue;
      t1 = number_at(std::string_view(line).substr(0, line.find(',')), csv, number);
      if (n == 0) t0 = t1;
      ++n;
      if (watched.empty()) continue;
      const std::vector<double> fields = row_numbers(line, out.names.size(), csv, number);
      for (const auto& [k, c] : watched) {
        if (!std::isfinite(fields[k])) first_nonfinite.emplace(c, t1);
      }
    }
  }
  out.columns.assign(out.names.size(), {});
  if (n == 0) return out;
  const double span = t1 - t0;
  std::size_t wanted = 1;
  if (span > 0) {
    const double frames = std::ceil(span * options.fps) + 1.0;
    wanted = frames >= double(options.max_frames) ? options.max_frames
                                                  : std::max<std::size_t>(2, std::size_t(frames));
  }
  // pass 2: row j is shown when a target time lies in [t_j, t_(j+1)) (as shown_frames), or is
  // the last
  const auto keep = [&](const std::string& row, long number) {
    const std::vector<double> values = row_numbers(row, out.names.size(), csv, number);
    for (std::size_t j = 0; j < values.size(); ++j) out.columns[j].push_back(values[j]);
  };
  std::ifstream in = open_csv(csv);
  std::string line, previous;
  long previous_number = 0;
  std::size_t k = 0;
  std::getline(in, line);
  for (long number = 2; std::getline(in, line); ++number) {
    if (line.empty() || line == "\r") continue;
    const double t = number_at(std::string_view(line).substr(0, line.find(',')), csv, number);
    if (previous_number != 0) {
      bool shown = wanted >= n;
      while (k < wanted &&
             t0 + span * double(k) / double(std::max<std::size_t>(wanted - 1, 1)) < t) {
        shown = true;
        ++k;
      }
      if (shown) keep(previous, previous_number);
    }
    previous.swap(line);
    previous_number = number;
  }
  keep(previous, previous_number);
  return out;
}

std::string python_json(const json& json_value) {
  std::string out;
  write_python_json(json_value, out);
  return out;
}

std::string json_for_html(const json& data) {
  std::string text = python_json(data);
  text = replace_all(text, "<", "\\u003c");
  text = replace_all(text, ">", "\\u003e");
  return replace_all(text, "&", "\\u0026");
}

std::string fill_viewer_template(std::string_view page_template, std::string_view three,
                                 const json& data) {
  const json& model = data.at("model");
  const std::string title =
      html_escape("ukdyn: " + (model.is_string() ? model.get<std::string>() : model.dump()));
  const std::string keys[] = {"<!--UKDYN_TITLE-->", "/*UKDYN_THREE*/", "/*UKDYN_DATA*/null"};
  const std::string values[] = {title, replace_all(three, "</script", "<\\/script"),
                                json_for_html(data)};
  // one pass: what is put in is never searched for a placeholder
  std::string out;
  std::size_t start = 0;
  while (true) {
    std::size_t at = std::string_view::npos, which = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t found = page_template.find(keys[i], start);
      if (found < at) {
        at = found;
        which = i;
      }
    }
    if (at == std::string_view::npos) break;
    out.append(page_template.substr(start, at - start)).append(values[which]);
    start = at + keys[which].size();
  }
  out.append(page_template.substr(start));
  return out;
}

}  // namespace ukdyn::cli
