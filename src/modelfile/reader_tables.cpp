// SPDX-License-Identifier: BSD-3-Clause
// tables: of a model file — measured data (a CSV file beside the model, or the columns written
// in the file) declared to the expression set as functions table.column(x) (modelfile/table.hpp,
// docs/model-format.md "Tables"). Every error is located: at the table's entry in the model
// file, and for a CSV's cell at FILE.csv:LINE:COLUMN in the message.

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "modelfile/reader.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/modelfile/table.hpp"

namespace ukdyn::model_reader {

namespace {

const std::vector<std::string> kTableKeys = {"file",    "data",          "x",
                                             "columns", "interpolation", "extrapolation"};

std::string trimmed(const std::string& s, std::size_t& first) {
  std::size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r')) --e;
  first = b;
  return s.substr(b, e - b);
}

// a file name ending in .h5 or .hdf5 (any case): an HDF5 file
bool is_hdf5(const std::string& name) {
  std::string lower = name;
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  return lower.ends_with(".h5") || lower.ends_with(".hdf5");
}

// the number written in `cell` (the whole of it), or false
bool parse_number(const std::string& cell, double& value) {
  if (cell.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(cell.c_str(), &end);
  return end == cell.c_str() + cell.size();
}

}  // namespace

void Reader::read_tables(const YAML::Node& root) {
  const YAML::Node tables = root["tables"];
  if (tables && !tables.IsMap()) {
    fail(tables, "tables: must be a mapping of table names to tables",
         "tables: {ground: {file: ground.csv, x: t}}");
  }
  // the caller's tables: each declared by the file
  if (given_tables_ != nullptr) {
    for (const auto& [name, data] : *given_tables_) {
      if (!tables || !tables[name]) {
        std::vector<std::string> declared;
        if (tables) {
          for (const auto& kv : tables) declared.push_back(kv.first.Scalar());
        }
        throw ModelError(file_, 0, 0, "the table '" + name + "' given is not declared in tables:",
                         declared.empty() ? "declare it: tables: {" + name + ": {x: t}}"
                                          : "the model's tables are " + join(declared));
      }
    }
  }
  if (!tables) return;
  for (const auto& entry : tables) {
    const std::string name = entry.first.Scalar();
    const YAML::Node& table = entry.second;
    const std::string what = "table '" + name + "'";
    if (!is_identifier(name)) {
      fail(entry.first, "'" + name + "' is not a table name",
           "a letter or '_', then letters, digits, '_'");
    }
    if (!table.IsMap()) {
      fail(table, what + " must be a mapping (file: or data:, x:, interpolation:, …)");
    }
    for (const auto& kv : table) {
      const std::string key = kv.first.Scalar();
      if (std::find(kTableKeys.begin(), kTableKeys.end(), key) == kTableKeys.end()) {
        fail(kv.first, "unknown key '" + key + "' in " + what, "the keys are " + join(kTableKeys));
      }
    }
    const TableData* given = nullptr;
    if (given_tables_ != nullptr) {
      if (const auto it = given_tables_->find(name); it != given_tables_->end())
        given = &it->second;
    }
    if (table["file"] && table["data"]) {
      fail(table, what + " has both file: and data:", "keep one of them");
    }
    if (!table["file"] && !table["data"] && given == nullptr) {
      fail(table,
           what +
               " has no data: give file: (a CSV file) or data: (the columns written "
               "here), or the table from the program that loads the model",
           "file: ground.csv (with a header row, relative to the model file), or data: {t: [0, "
           "1], a: [0, 2]}");
    }
    TableColumns columns;
    std::string source;
    YAML::Node where = table["file"] ? table["file"] : table["data"] ? table["data"] : table;
    if (given != nullptr) {
      // (replaces file: or data:, as an override replaces a parameter's value)
      where = table;
      source = "the table given";
      columns = given_data(table, *given, what);
    } else if (table["file"]) {
      if (!where.IsScalar()) fail(where, "file: of " + what + " must be a file name");
      source = where.Scalar();
      columns = is_hdf5(source) ? read_hdf5_table(where, table, what) : read_csv(where, what);
    } else {
      source = file_;
      columns = read_data(where, what);
    }

    if (columns.names.empty()) fail(where, what + " has no columns");
    // the abscissa: x: (default: the first column)
    std::string x_name = columns.names.front();
    if (const YAML::Node x = table["x"]) {
      x_name = x.Scalar();
      if (std::find(columns.names.begin(), columns.names.end(), x_name) == columns.names.end()) {
        fail(x, what + " has no column '" + x_name + "'", "its columns are " + join(columns.names));
      }
    }
    const std::size_t xi = std::size_t(
        std::find(columns.names.begin(), columns.names.end(), x_name) - columns.names.begin());
    // the columns called as functions: columns: (default: every other one)
    std::vector<std::string> called;
    if (const YAML::Node c = table["columns"]) {
      if (!c.IsSequence()) fail(c, "columns: of " + what + " must be a list of column names");
      for (const auto& n : c) {
        if (std::find(columns.names.begin(), columns.names.end(), n.Scalar()) ==
            columns.names.end()) {
          fail(n, what + " has no column '" + n.Scalar() + "'",
               "its columns are " + join(columns.names));
        }
        called.push_back(n.Scalar());
      }
    } else {
      for (const auto& n : columns.names) {
        if (n != x_name) called.push_back(n);
      }
    }
    if (called.empty()) fail(table, what + " has no column besides its abscissa '" + x_name + "'");

    const auto choice = [&](const char* key, const std::vector<std::string>& names, int dflt) {
      const YAML::Node n = table[key];
      if (!n) return dflt;
      const auto it = std::find(names.begin(), names.end(), n.Scalar());
      if (it == names.end()) {
        fail(n, std::string(key) + ": of " + what + " is '" + n.Scalar() + "'",
             "one of " + join(names));
      }
      return int(it - names.begin());
    };
    const auto interpolation = expr::Interpolation(
        choice("interpolation", {"step", "linear", "cubic"}, int(expr::Interpolation::kLinear)));
    const auto extrapolation = expr::Extrapolation(
        choice("extrapolation", {"error", "hold", "linear"}, int(expr::Extrapolation::kError)));

    // rows: enough for the interpolation, the abscissa strictly increasing
    const std::vector<double>& x = columns.values[xi];
    const std::size_t least = interpolation == expr::Interpolation::kCubic ? 4 : 2;
    if (x.size() < least) {
      fail(where,
           what + " has " + format_number(x.size()) + (x.size() == 1 ? " row" : " rows") + "; " +
               expr::to_string(interpolation) + " interpolation needs at least " +
               format_number(least),
           least == 4 ? "give more rows, or interpolation: linear" : "give more rows");
    }
    const auto at_row = [&](std::size_t i) {
      return columns.lines[i] > 0 ? source + ":" + format_number(columns.lines[i]) + ": "
                                  : "row " + format_number(i + 1) + ": ";
    };
    for (std::size_t i = 1; i < x.size(); ++i) {
      if (!(x[i] > x[i - 1])) {
        fail(where,
             "in " + what + ": " + at_row(i) + "the abscissa '" + x_name +
                 "' is not strictly increasing (" + format_number(x[i]) + " after " +
                 format_number(x[i - 1]) + ")",
             "sort the rows by " + x_name + ", and give each value once");
      }
    }
    for (const auto& c : called) {
      const std::size_t ci = std::size_t(std::find(columns.names.begin(), columns.names.end(), c) -
                                         columns.names.begin());
      try {
        set_->add_table_column(name + "." + c, std::make_shared<const expr::TableColumn>(
                                                   name + "." + c, x, columns.values[ci],
                                                   interpolation, extrapolation, source));
      } catch (const std::invalid_argument& e) {
        fail(where, std::string("in ") + what + ": " + e.what());
      }
    }
  }
}

std::filesystem::path Reader::table_path(const YAML::Node& where, const std::string& what) {
  const std::filesystem::path path = model_relative_path(file_, where.Scalar());
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    fail(where, "cannot read " + path.string() + ", the file of " + what,
         std::filesystem::exists(path, ec)
             ? "it is not a regular file"
             : "no such file (a relative path is read from the model file's directory)");
  }
  if (std::filesystem::file_size(path, ec) > kMaxModelFileBytes) {
    fail(where, path.string() + " is larger than " + format_number(kMaxModelFileBytes >> 20) +
                    " MB, the largest table read");
  }
  return path;
}

TableColumns Reader::read_hdf5_table(const YAML::Node& where, const YAML::Node& table,
                                     const std::string& what) {
  const std::string path = table_path(where, what).string();
  TableColumns out;
  try {
    if (const YAML::Node c = table["columns"]) {
      // the datasets named: x: (default t) and columns:
      if (!c.IsSequence()) fail(c, "columns: of " + what + " must be a list of dataset names");
      out.names.push_back(table["x"] ? table["x"].Scalar() : "t");
      for (const auto& n : c) {
        if (std::find(out.names.begin(), out.names.end(), n.Scalar()) == out.names.end())
          out.names.push_back(n.Scalar());
      }
      for (const auto& n : out.names) out.values.push_back(read_hdf5_field(path, n));
    } else {
      // every column of a table ukdyn wrote (write_table_hdf5: a run's trajectory.h5) whose
      // name is an identifier (t, x, x_dot, an output; not lambda.rod)
      for (auto& [name, values] : read_table_hdf5(path)) {
        if (!is_identifier(name)) continue;
        out.names.push_back(name);
        out.values.push_back(std::move(values));
      }
    }
  } catch (const std::runtime_error& e) {
    fail(where, "in " + what + ": " + e.what(),
         "an HDF5 table is its 1-D datasets: name them with x: and columns:");
  }
  for (std::size_t k = 1; k < out.values.size(); ++k) {
    if (out.values[k].size() != out.values[0].size()) {
      fail(where, "in " + what + ": the dataset '" + out.names[k] + "' has " +
                      format_number(out.values[k].size()) + " values, '" + out.names[0] + "' " +
                      format_number(out.values[0].size()));
    }
  }
  for (std::size_t k = 0; k < out.values.size(); ++k) {
    for (const double v : out.values[k]) {
      if (!std::isfinite(v)) {
        fail(where, "in " + what + ": the dataset '" + out.names[k] + "' holds " +
                        format_number(v) + " (values must be finite)");
      }
    }
  }
  out.lines.assign(out.values.empty() ? 0 : out.values[0].size(), 0);
  return out;
}

TableColumns Reader::read_csv(const YAML::Node& where, const std::string& what) {
  const std::string& name = where.Scalar();
  const std::filesystem::path path = table_path(where, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(where, "cannot read " + path.string() + ", the file of " + what);
  const auto at = [&](int line, std::size_t column) {
    return "in " + what + ": " + name + ":" + format_number(line) + ":" + format_number(column) +
           ": ";
  };
  TableColumns out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::size_t lead = 0;
    const std::string body = trimmed(line, lead);
    if (body.empty() || body[0] == '#') continue;  // blank lines and comments
    // the cells, with their 1-based columns
    std::vector<std::pair<std::string, std::size_t>> cells;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = line.find(',', start);
      const std::string raw =
          line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      std::size_t first = 0;
      std::string cell = trimmed(raw, first);
      if (cell.size() >= 2 && cell.front() == '"' && cell.back() == '"') {
        cell = cell.substr(1, cell.size() - 2);
      }
      cells.emplace_back(cell, start + first + 1);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    if (out.names.empty()) {  // the header
      for (const auto& [cell, column] : cells) {
        if (!is_identifier(cell)) {
          fail(where, at(number, column) + "the column name '" + cell + "' is not a name",
               "the header row names the columns with identifiers (t, acc, x_1)");
        }
        if (std::find(out.names.begin(), out.names.end(), cell) != out.names.end()) {
          fail(where, at(number, column) + "the column '" + cell + "' is named twice");
        }
        out.names.push_back(cell);
      }
      out.values.resize(out.names.size());
      continue;
    }
    if (cells.size() != out.names.size()) {
      fail(where, at(number, 1) + format_number(cells.size()) + " cells, but the header names " +
                      format_number(out.names.size()) + " columns");
    }
    for (std::size_t k = 0; k < cells.size(); ++k) {
      double v = 0.0;
      if (!parse_number(cells[k].first, v)) {
        fail(where, at(number, cells[k].second) + "'" + cells[k].first +
                        "' is not a number (column '" + out.names[k] + "')");
      }
      if (!std::isfinite(v)) {
        fail(where, at(number, cells[k].second) + "'" + cells[k].first +
                        "' is not a finite number (column '" + out.names[k] + "')");
      }
      out.values[k].push_back(v);
    }
    out.lines.push_back(number);
  }
  if (out.names.empty()) {
    fail(where, "in " + what + ": " + name + " is empty",
         "a CSV file with a header row naming the columns");
  }
  return out;
}

TableColumns Reader::read_data(const YAML::Node& data, const std::string& what) {
  if (!data.IsMap() || data.size() == 0) {
    fail(data, "data: of " + what + " must map column names to lists of numbers",
         "data: {t: [0, 1, 2], a: [0, 1, 4]}");
  }
  TableColumns out;
  for (const auto& kv : data) {
    const std::string column = kv.first.Scalar();
    if (!is_identifier(column)) fail(kv.first, "'" + column + "' is not a column name");
    if (!kv.second.IsSequence()) {
      fail(kv.second, "column '" + column + "' of " + what + " must be a list of numbers");
    }
    std::vector<double> values;
    for (const auto& v : kv.second) {
      double x = 0.0;
      if (!v.IsScalar() || !parse_number(v.Scalar(), x) || !std::isfinite(x)) {
        fail(v, "in column '" + column + "' of " + what + ": '" + v.Scalar() +
                    "' is not a finite number");
      }
      values.push_back(x);
    }
    if (!out.values.empty() && values.size() != out.values.front().size()) {
      fail(kv.second, "column '" + column + "' of " + what + " has " +
                          format_number(values.size()) + " values, column '" + out.names.front() +
                          "' " + format_number(out.values.front().size()));
    }
    out.names.push_back(column);
    out.values.push_back(std::move(values));
  }
  out.lines.assign(out.values.front().size(), 0);
  return out;
}

TableColumns Reader::given_data(const YAML::Node& table, const TableData& data,
                                const std::string& what) {
  if (data.empty()) fail(table, "the " + what + " given has no columns");
  TableColumns out;
  for (const auto& [column, values] : data) {
    if (!is_identifier(column)) {
      fail(table, "the " + what + " given has the column name '" + column + "', not a name");
    }
    if (std::find(out.names.begin(), out.names.end(), column) != out.names.end()) {
      fail(table, "the " + what + " given names the column '" + column + "' twice");
    }
    if (!out.values.empty() && values.size() != out.values.front().size()) {
      fail(table, "the " + what + " given has " + format_number(values.size()) +
                      " values in column '" + column + "' and " +
                      format_number(out.values.front().size()) + " in '" + out.names.front() + "'");
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (!std::isfinite(values[i])) {
        fail(table, "the " + what + " given holds " + format_number(values[i]) + " in column '" +
                        column + "', row " + format_number(i + 1) + " (values must be finite)");
      }
    }
    out.names.push_back(column);
    out.values.push_back(values);
  }
  out.lines.assign(out.values.front().size(), 0);
  return out;
}

}  // namespace ukdyn::model_reader
