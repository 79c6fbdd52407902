// SPDX-License-Identifier: BSD-3-Clause
/// @file core/units.hpp
/// The units a model declares for its numbers (docs/model-format.md, "Units"): length, mass
/// and time, SI by default, and the labels of the quantities derived from them. Labels, but
/// for the defaults that are times (docs/model-format.md, "Units"): a unit changes no number. A
/// model file's `units:` fills one (Model::unit_system); a run's messages take theirs from
/// SimulationOptions::units.
#pragma once

#include <array>
#include <string>
#include <string_view>

namespace ukdyn {

/// The base units of a model (`units: {length: mm, mass: g, time: ms}`) and the labels derived
/// from them, for every printed or plotted unit (the console, summary.json's `unit_system`, the
/// plots). A derived unit is the product of the base units — force mass·length/time², energy
/// mass·length²/time², power mass·length²/time³ — named N, J and W only when all three are SI
/// (m, kg, s), so that a label is never wrong: 4.41e3 in g, mm and ms is "4.41e3 g·mm²/ms²", not
/// "J". Angles are in rad whatever the system (a body's angle, a revolute joint's). Cost of each
/// label: a few string concatenations.
struct UnitSystem {
  std::string length = "m";  ///< unit of length (kLengths)
  std::string mass = "kg";   ///< unit of mass (kMasses)
  std::string time = "s";    ///< unit of time (kTimes)

  /// The accepted units of length (`units:` refuses others, naming these).
  static constexpr std::array<std::string_view, 6> kLengths{"m", "mm", "cm", "km", "um", "nm"};
  /// The accepted units of mass.
  static constexpr std::array<std::string_view, 4> kMasses{"kg", "g", "mg", "t"};
  /// The accepted units of time.
  static constexpr std::array<std::string_view, 5> kTimes{"s", "ms", "us", "min", "h"};

  /// Seconds per time unit (1e-3 for ms, 3600 for h). Cost O(1).
  double seconds() const {
    return time == "ms"    ? 1e-3
           : time == "us"  ? 1e-6
           : time == "min" ? 60.0
           : time == "h"   ? 3600.0
                           : 1.0;
  }
  /// Time units per second, 1/seconds() (1000 for ms, exact for ms and us). Cost O(1).
  double per_second() const { return time == "ms" ? 1e3 : time == "us" ? 1e6 : 1.0 / seconds(); }
  /// Metres per length unit (1e-3 for mm). Cost O(1).
  double metres() const {
    return length == "mm"   ? 1e-3
           : length == "cm" ? 1e-2
           : length == "km" ? 1e3
           : length == "um" ? 1e-6
           : length == "nm" ? 1e-9
                            : 1.0;
  }
  /// Kilograms per mass unit (1e-3 for g, 1e3 for t, the tonne). Cost O(1).
  double kilograms() const {
    return mass == "g" ? 1e-3 : mass == "mg" ? 1e-6 : mass == "t" ? 1e3 : 1.0;
  }
  /// True when a coordinate in `unit` is an angle — "rad", "deg" or "°" — rather than a length:
  /// its column of A is weighed by 1 in the run's violation scales, not by the run's length
  /// (SimulationOptions::angle_coordinates; docs/simulation.md, "Scales and tolerances", angle
  /// columns). Any other unit, none (""), and "1" (a quaternion's component, which that section
  /// says why) count as a length. Cost O(1).
  static bool is_angle(std::string_view unit) {
    return unit == "rad" || unit == "deg" || unit == "°";
  }
  /// True when length, mass and time are m, kg and s.
  bool is_si() const { return length == "m" && mass == "kg" && time == "s"; }
  /// `unit`/time ("1/time" for unit "1" or "", a number without unit): the rate of a quantity
  /// in `unit`; per time² with order 2.
  std::string rate(const std::string& unit, int order = 1) const {
    const std::string per = order == 2 ? time + "²" : time;
    return unit.empty() || unit == "1" ? "1/" + per : unit + "/" + per;
  }
  /// length/time.
  std::string velocity() const { return rate(length); }
  /// length/time².
  std::string acceleration() const { return rate(length, 2); }
  /// N in SI units, else mass·length/time².
  std::string force() const { return is_si() ? "N" : mass + "·" + length + "/" + time + "²"; }
  /// J in SI units, else mass·length²/time² (also a torque's: N·m in SI units, torque()).
  std::string energy() const { return is_si() ? "J" : mass + "·" + length + "²/" + time + "²"; }
  /// N·m in SI units, else mass·length²/time² (a torque about an axis).
  std::string torque() const { return is_si() ? "N·m" : energy(); }
  /// W in SI units, else mass·length²/time³.
  std::string power() const { return is_si() ? "W" : mass + "·" + length + "²/" + time + "³"; }
};

}  // namespace ukdyn
