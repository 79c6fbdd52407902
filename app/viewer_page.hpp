// SPDX-License-Identifier: BSD-3-Clause
// The viewer's page, animation.html, written by the command itself (issue #33 item 2): the same
// page as Python's Result.save_animation (python/ukdyn/viewer.py) for the same run, by the same
// rules, without a Python process. Two stages:
//   viewer_data.cpp  the run's samples → the page's data (decimated to the display rate and
//                    rounded to what a screen shows; viewer.py's scene_data)
//   viewer_page.cpp  the trajectory's rows shown (viewer.py's read_csv), the data as JSON text
//                    that an HTML parser cannot take for markup, and the template filled
// The data is a nlohmann::ordered_json (its keys in viewer.py's order) written in the form of
// Python's json.dumps, so that the two writers' pages are the same bytes.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace ukdyn::cli {

/// The decimation and rounding of the page (viewer.py's FPS, MAX_FRAMES, DIGITS).
struct ViewerOptions {
  double fps = 30.0;              ///< frames per simulated second
  std::size_t max_frames = 3000;  ///< the most frames a page holds
  int digits = 4;                 ///< significant digits of forces
};

/// A trajectory's columns: names (the CSV header) and values (one vector per name).
struct ViewerColumns {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
};

/// The indices of the samples shown (viewer.py's _frames): about fps per simulated second of
/// t (every sample when they are sparser), at most max_frames, always the first and the last.
/// Cost: O(size of t).
std::vector<std::size_t> shown_frames(const std::vector<double>& t, const ViewerOptions& options);

/// v with `digits` significant digits (Python's float("%.*g" % (digits, v))), as a JSON number:
/// an integer when it is whole and below 1e15, null when v is not finite.
nlohmann::ordered_json round_significant(double v, int digits);

/// v rounded half to even to `decimals` decimal places (negative: to tens, hundreds …), as
/// Python's round(v, decimals) does, on v's exact binary value; a JSON number as
/// round_significant.
nlohmann::ordered_json round_fixed(double v, int decimals);

/// The page's data (viewer.py's scene_data): the scene of viewer_scene_json (parsed) with each
/// body's, joint's, point's and frame's samples decimated (shown_frames) and rounded, the
/// control's requirements, the desired paths, the contacts of `visual: contacts:` with their
/// impacts (from `contact_events`, summary.json's list of the run's contact events) and the
/// scales of the force arrows. Throws std::runtime_error naming a column the scene needs and
/// the trajectory lacks. Cost: O(columns × frames shown + contact events).
nlohmann::ordered_json viewer_page_data(
    const nlohmann::ordered_json& scene, const ViewerColumns& run,
    const ViewerOptions& options = {},
    const nlohmann::ordered_json& contact_events = nlohmann::ordered_json::array());

/// The contact events of a run's summary.json (viewer.py's read_contact_events): its
/// `contact_events` list, or an empty list when the file is missing, not JSON or has none.
/// Cost: one read of the file.
nlohmann::ordered_json read_contact_events(const std::filesystem::path& summary);

/// The columns visual.<point>.<axis> of the scene's points (viewer.py's _point_columns).
std::vector<std::string> point_columns(const nlohmann::ordered_json& scene);

/// The warnings (one line each, "warning: visual point …") for the visual points that are not
/// finite; first maps a point's column to the first time it is not (viewer.py's
/// nonfinite_warnings).
std::vector<std::string> nonfinite_warnings(const nlohmann::ordered_json& scene,
                                            const std::map<std::string, double>& first);

/// The CSV's names and the columns of the rows shown only (viewer.py's read_csv, two passes:
/// memory O(frames × columns) however long the run); `first_nonfinite` gets the first time
/// each column named in `watch` is not finite, over every row. Throws std::runtime_error
/// naming the file (and line) when it cannot be read or a field is not a number.
ViewerColumns read_viewer_csv(const std::filesystem::path& csv, const ViewerOptions& options,
                              const std::vector<std::string>& watch,
                              std::map<std::string, double>& first_nonfinite);

/// `json` as Python's json.dumps(json, separators=(",", ":"), ensure_ascii=True,
/// allow_nan=False) writes it: numbers as Python's repr, every character beyond ASCII as a
/// \u escape. Throws std::invalid_argument for a number that is not finite.
std::string python_json(const nlohmann::ordered_json& json);

/// `data` as JSON text that an HTML parser takes for nothing but the text of its
/// <script type="application/json"> element: python_json with every <, > and & written as \u
/// escapes (viewer.py's _json_for_html; U+2028/9 are escaped as all beyond ASCII).
std::string json_for_html(const nlohmann::ordered_json& data);

/// The page: the template with its three placeholders filled in one pass (what is put in is
/// never searched for a placeholder): <!--UKDYN_TITLE--> by the title, HTML-escaped;
/// /*UKDYN_THREE*/ by three.js (`three`, with no "</script" left in it); /*UKDYN_DATA*/null by
/// json_for_html(data). The title is "ukdyn: " and the model's name.
std::string fill_viewer_template(std::string_view page_template, std::string_view three,
                                 const nlohmann::ordered_json& data);

}  // namespace ukdyn::cli
