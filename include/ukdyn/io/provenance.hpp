// SPDX-License-Identifier: BSD-3-Clause
/// @file io/provenance.hpp
/// What a run was made from, so that its directory says how to make it again: the model (name,
/// file, SHA-256 of its text), every parameter with the overridden ones marked, the command line,
/// the ukdyn version and commit (summary.json's `provenance`, `ukdyn run --from-summary`).
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ukdyn {

/// The library's version, "MAJOR.MINOR.PATCH" (CMake's project version).
const char* version();

/// The commit the library was built from: `git describe --always --dirty --abbrev=12` at build
/// time ("…-dirty" when the tree had changes), or "unknown" outside a git checkout.
const char* commit();

/// SHA-256 of `data` (FIPS 180-4) as 64 lowercase hexadecimal digits. Cost O(size).
std::string sha256_hex(std::string_view data);

/// One parameter of a run: its value, and whether an override (`--set`, load_model's
/// `overrides`) gave it.
struct ProvenanceParameter {
  std::string name;         ///< as declared in `parameters:`
  double value = 0.0;       ///< the value the run used
  bool overridden = false;  ///< given by an override, not by the file
};

/// What write_summary_json records under `provenance` (ukdyn run fills it in).
struct RunProvenance {
  std::string model_name;    ///< `name:` of the model
  std::string model_file;    ///< the file as given on the command line (absolute path)
  std::string example;       ///< the built-in example's name, or "" for a file
  std::string model_sha256;  ///< sha256_hex of the model's text
  std::vector<ProvenanceParameter> parameters;  ///< every parameter, in name order
  std::vector<std::string> arguments;           ///< the command line, argv[0] first
  /// the time's unit (column `t`), each coordinate's and output expression's unit
  /// (Model::coordinate_units, output_units; "" not known), by column name: summary.json's
  /// `units`, which the plots label their axes with; empty: not written
  std::vector<std::pair<std::string, std::string>> units;
  /// the model's base units and the labels derived from them (Model::units, UnitSystem):
  /// length, mass, time, velocity, force, energy, power, by name: summary.json's
  /// `unit_system`, which the plots derive every other label from; empty: not written
  std::vector<std::pair<std::string, std::string>> unit_system;
};

}  // namespace ukdyn
