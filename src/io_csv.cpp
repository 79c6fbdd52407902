// CSV writer of a trajectory: one header line, then one row per sample.
#include "ukdyn/io.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace ukdyn {
namespace {

constexpr const char* kWho = "ukdyn::write_csv";

// A header field, quoted as RFC 4180 asks when it holds a comma, a quote or a line break.
void append_field(std::string& out, const std::string& name) {
  if (name.find_first_of(",\"\r\n") == std::string::npos) {
    out += name;
    return;
  }
  out += '"';
  for (char c : name) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
}

// x in the shortest form that reads back bit for bit (std::to_chars: locale-independent);
// NaN of either sign as "nan", infinities as "inf" / "-inf".
void append_number(std::string& out, double x) {
  if (std::isnan(x)) {
    out += "nan";
    return;
  }
  char buf[32];  // the longest shortest form, "-2.2250738585072014e-308", has 24 characters
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  UKDYN_CHECK(ec == std::errc(), "std::to_chars needs at most 24 characters for a double");
  out.append(buf, end);
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

[[noreturn]] void throw_io_error(const std::string& path, const char* doing, int err) {
  throw std::runtime_error(std::string(kWho) + ": cannot " + doing + " '" + path +
                           "': " + (err != 0 ? std::strerror(err) : "unknown reason"));
}

// The header names, in column order (sizes already checked).
std::vector<std::string> columns(const Trajectory& traj) {
  const auto& x = traj.coordinate_names;
  const std::size_t K = traj.constraint_names.size();
  std::vector<std::string> cols;
  cols.reserve(1 + 5 * x.size() + std::size_t(traj.m) + 2 * K + 4);

  // t, then q, q', q'', Qc_ideal, Qc_nonideal by coordinate
  cols.emplace_back("t");
  for (const auto& name : x) cols.push_back(name);
  for (const auto& name : x) cols.push_back(name + "_dot");
  for (const auto& name : x) cols.push_back(name + "_ddot");
  for (const auto& name : x) cols.push_back("Qc_ideal." + name);
  for (const auto& name : x) cols.push_back("Qc_nonideal." + name);

  // lambda by constraint row; the row number only when a constraint has several rows
  for (std::size_t k = 0; k < K; ++k) {
    const std::string base = "lambda." + traj.constraint_names[k];
    const Index rows = traj.constraint_rows[k];
    if (rows == 1) {
      cols.push_back(base);
    } else {
      for (Index r = 0; r < rows; ++r) cols.push_back(base + "." + std::to_string(r));
    }
  }

  // violations: one per constraint, then the velocity level of the holonomic ones
  for (const auto& name : traj.constraint_names) cols.push_back("violation." + name);
  for (std::size_t k = 0; k < K; ++k) {
    if (traj.constraint_kinds[k] == ConstraintKind::kHolonomic) {
      cols.push_back("violation_velocity." + traj.constraint_names[k]);
    }
  }

  cols.emplace_back("kinetic_energy");
  cols.emplace_back("potential_energy");
  cols.emplace_back("energy");
  cols.emplace_back("work_nonideal");
  return cols;
}

}  // namespace

std::vector<std::string> csv_columns(const Trajectory& traj) {
  traj.check_consistent("ukdyn::csv_columns");
  return columns(traj);
}

std::vector<CsvColumn> csv_table(const Trajectory& traj) {
  traj.check_consistent("ukdyn::csv_table");
  const std::vector<std::string> names = columns(traj);
  const std::size_t N = traj.t.size(), n = std::size_t(traj.n), m = std::size_t(traj.m);
  const std::size_t K = traj.constraint_names.size();
  std::vector<CsvColumn> table;
  table.reserve(names.size());
  auto next = [&] {
    table.push_back(CsvColumn{names[table.size()], std::vector<double>(N)});
    return &table.back().values;
  };
  *next() = traj.t;
  auto field = [&](const std::vector<double>& f, std::size_t width) {
    for (std::size_t j = 0; j < width; ++j) {
      std::vector<double>& v = *next();
      for (std::size_t i = 0; i < N; ++i) v[i] = f[i * width + j];
    }
  };
  field(traj.q, n);
  field(traj.qd, n);
  field(traj.qdd, n);
  field(traj.Qc_ideal, n);
  field(traj.Qc_nonideal, n);
  field(traj.lambda, m);
  for (std::size_t k = 0; k < K; ++k) {
    const bool holonomic = traj.constraint_kinds[k] == ConstraintKind::kHolonomic;
    const std::vector<double>& f = holonomic ? traj.position_violation : traj.velocity_violation;
    std::vector<double>& v = *next();
    for (std::size_t i = 0; i < N; ++i) v[i] = f[i * K + k];
  }
  for (std::size_t k = 0; k < K; ++k) {
    if (traj.constraint_kinds[k] != ConstraintKind::kHolonomic) continue;
    std::vector<double>& v = *next();
    for (std::size_t i = 0; i < N; ++i) v[i] = traj.velocity_violation[i * K + k];
  }
  for (const auto* f : {&traj.kinetic_energy, &traj.potential_energy, &traj.energy,
                        &traj.work_nonideal}) {
    *next() = *f;
  }
  return table;
}

void write_csv(const Trajectory& traj, const std::string& path) { write_csv(traj, path, {}); }

void write_csv(const Trajectory& traj, const std::string& path,
               const std::vector<CsvColumn>& extra) {
  traj.check_consistent(kWho);
  std::vector<std::string> cols = columns(traj);
  const std::size_t N = traj.t.size();
  for (const CsvColumn& e : extra) {
    if (e.values.size() != N) {
      throw std::invalid_argument(std::string(kWho) + ": extra column '" + e.name + "' has " +
                                  std::to_string(e.values.size()) + " values, expected N = " +
                                  std::to_string(N));
    }
    cols.push_back(e.name);
  }
  const std::size_t n = std::size_t(traj.n), m = std::size_t(traj.m);
  const std::size_t K = traj.constraint_names.size();

  errno = 0;
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
  if (!file) throw_io_error(path, "open", errno);

  // rows are built in one buffer, written out whenever it passes kFlushAt bytes
  constexpr std::size_t kFlushAt = std::size_t(1) << 18;
  std::string buf;
  buf.reserve(kFlushAt + 32 * cols.size() + 64);
  auto flush = [&] {
    if (!buf.empty() && std::fwrite(buf.data(), 1, buf.size(), file.get()) != buf.size()) {
      throw_io_error(path, "write", errno);
    }
    buf.clear();
  };

  // header
  for (std::size_t c = 0; c < cols.size(); ++c) {
    if (c > 0) buf += ',';
    append_field(buf, cols[c]);
  }
  buf += '\n';

  // one row per sample, in the order of csv_columns()
  auto row_of = [&](const std::vector<double>& f, std::size_t i, std::size_t width) {
    for (std::size_t j = 0; j < width; ++j) {
      buf += ',';
      append_number(buf, f[i * width + j]);
    }
  };
  for (std::size_t i = 0; i < N; ++i) {
    append_number(buf, traj.t[i]);
    row_of(traj.q, i, n);
    row_of(traj.qd, i, n);
    row_of(traj.qdd, i, n);
    row_of(traj.Qc_ideal, i, n);
    row_of(traj.Qc_nonideal, i, n);
    row_of(traj.lambda, i, m);
    // violation: position level if holonomic, else velocity level (0 for the acceleration kind)
    for (std::size_t k = 0; k < K; ++k) {
      buf += ',';
      const bool holonomic = traj.constraint_kinds[k] == ConstraintKind::kHolonomic;
      append_number(buf, (holonomic ? traj.position_violation : traj.velocity_violation)[i * K + k]);
    }
    for (std::size_t k = 0; k < K; ++k) {
      if (traj.constraint_kinds[k] != ConstraintKind::kHolonomic) continue;
      buf += ',';
      append_number(buf, traj.velocity_violation[i * K + k]);
    }
    for (const auto* f : {&traj.kinetic_energy, &traj.potential_energy, &traj.energy,
                          &traj.work_nonideal}) {
      buf += ',';
      append_number(buf, (*f)[i]);
    }
    for (const CsvColumn& e : extra) {
      buf += ',';
      append_number(buf, e.values[i]);
    }
    buf += '\n';
    if (buf.size() >= kFlushAt) flush();
  }
  flush();

  // fclose writes what stdio still holds: its failure (a full disk) is a write error too
  errno = 0;
  if (std::fclose(file.release()) != 0) {
    throw_io_error(path, "write", errno);
  }
}

}  // namespace ukdyn
