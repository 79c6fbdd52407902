// SPDX-License-Identifier: BSD-3-Clause
// CSV writer of a trajectory: one header line, then one row per sample, written under a
// temporary name and renamed when complete.
#include "ukdyn/core/format.hpp"
#include "ukdyn/io/trajectory_files.hpp"

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

#include "io/atomic_file.hpp"

namespace ukdyn {
namespace {

constexpr const char* kCsvWho = "ukdyn::write_csv";

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

// One standard column: its header name and where its values are, field[i · width + index] for
// sample i.
struct ColumnRef {
  std::string name;
  const std::vector<double>* field;
  std::size_t width, index;
};

// The standard columns, in order (sizes already checked): the one description that the header,
// csv_table and the rows of write_csv read.
std::vector<ColumnRef> column_refs(const Trajectory& traj) {
  const auto& x = traj.coordinate_names;
  const std::size_t n = x.size(), m = std::size_t(traj.m);
  const std::size_t K = traj.constraint_names.size();
  std::vector<ColumnRef> cols;
  cols.reserve(1 + 5 * n + m + traj.unilateral.size() + 2 * K + 9);
  const auto scalar = [&](std::string name, const std::vector<double>& f) {
    cols.push_back(ColumnRef{std::move(name), &f, 1, 0});
  };

  // t, then q, q', q'', Qc_ideal, Qc_nonideal by coordinate
  scalar("t", traj.t);
  const auto by_coordinate = [&](const std::vector<double>& f, const char* prefix,
                                 const char* suffix) {
    for (std::size_t j = 0; j < n; ++j) cols.push_back(ColumnRef{prefix + x[j] + suffix, &f, n, j});
  };
  by_coordinate(traj.q, "", "");
  by_coordinate(traj.qd, "", "_dot");
  by_coordinate(traj.qdd, "", "_ddot");
  by_coordinate(traj.Qc_ideal, "Qc_ideal.", "");
  by_coordinate(traj.Qc_nonideal, "Qc_nonideal.", "");

  // lambda by constraint row; the row number only when a constraint has several rows
  std::size_t row = 0;
  for (std::size_t k = 0; k < K; ++k) {
    const std::string base = "lambda." + traj.constraint_names[k];
    const Index rows = traj.constraint_rows[k];
    for (Index r = 0; r < rows; ++r) {
      cols.push_back(
          ColumnRef{rows == 1 ? base : base + "." + format_number(r), &traj.lambda, m, row++});
    }
  }
  // the unilateral constraints' whole multipliers lambda + lambda_nonideal (their contact force)
  for (std::size_t u = 0; u < traj.unilateral.size(); ++u) {
    cols.push_back(
        ColumnRef{"lambda_total." + traj.constraint_names[std::size_t(traj.unilateral[u])],
                  &traj.lambda_total, traj.unilateral.size(), u});
  }

  // violations: one per constraint (position level if holonomic, else velocity level; 0 for
  // the acceleration kind), then the velocity level of the holonomic ones
  for (std::size_t k = 0; k < K; ++k) {
    const bool holonomic = traj.constraint_kinds[k] == ConstraintKind::kHolonomic;
    cols.push_back(ColumnRef{"violation." + traj.constraint_names[k],
                             holonomic ? &traj.position_violation : &traj.velocity_violation, K,
                             k});
  }
  for (std::size_t k = 0; k < K; ++k) {
    if (traj.constraint_kinds[k] == ConstraintKind::kHolonomic) {
      cols.push_back(ColumnRef{"violation_velocity." + traj.constraint_names[k],
                               &traj.velocity_violation, K, k});
    }
  }

  scalar("kinetic_energy", traj.kinetic_energy);
  scalar("potential_energy", traj.potential_energy);
  scalar("energy", traj.energy);
  scalar("work_nonideal", traj.work_nonideal);
  scalar("work_ideal", traj.work_ideal);
  scalar("work_drive", traj.work_drive);
  scalar("work_external", traj.work_external);
  scalar("work_control", traj.work_control);
  if (!traj.work_impact.empty()) scalar("work_impact", traj.work_impact);  // (unilateral contacts)
  scalar("energy_balance_residual", traj.energy_balance_residual);
  return cols;
}

}  // namespace

std::vector<std::string> csv_columns(const Trajectory& traj) {
  traj.check_consistent("ukdyn::csv_columns");
  std::vector<std::string> names;
  for (auto& c : column_refs(traj)) names.push_back(std::move(c.name));
  return names;
}

std::vector<CsvColumn> csv_table(const Trajectory& traj) {
  traj.check_consistent("ukdyn::csv_table");
  const std::size_t N = traj.t.size();
  std::vector<CsvColumn> table;
  for (auto& c : column_refs(traj)) {
    std::vector<double> values(N);
    for (std::size_t i = 0; i < N; ++i) values[i] = (*c.field)[i * c.width + c.index];
    table.push_back(CsvColumn{std::move(c.name), std::move(values)});
  }
  return table;
}

void write_csv(const Trajectory& traj, const std::string& path) { write_csv(traj, path, {}); }

struct CsvWriter::Impl {
  explicit Impl(const std::string& p) : path(p), out(p, kCsvWho), file(out.open_stdio()) {
    buf.reserve(kFlushAt + 4096);
  }
  // rows are built in one buffer, written out whenever it passes kFlushAt bytes
  static constexpr std::size_t kFlushAt = std::size_t(1) << 18;
  void flush() {
    if (!buf.empty() && std::fwrite(buf.data(), 1, buf.size(), file.get()) != buf.size()) {
      detail::throw_io_error(kCsvWho, path, "write", errno);
    }
    buf.clear();
  }
  std::string path;
  // a temporary beside `path`, renamed over it when complete (io/atomic_file.hpp)
  detail::AtomicFile out;
  std::unique_ptr<std::FILE, detail::FileCloser> file;
  std::string buf;
  std::vector<std::string> header;  // empty until the first append
};

CsvWriter::CsvWriter(const std::string& path) : impl_(new Impl(path)) {}

CsvWriter::~CsvWriter() { delete impl_; }

void CsvWriter::append(const Trajectory& traj, const std::vector<CsvColumn>& extra) {
  traj.check_consistent(kCsvWho);
  std::vector<ColumnRef> cols = column_refs(traj);
  const std::size_t N = traj.t.size();
  for (const CsvColumn& e : extra) {
    if (e.values.size() != N) {
      throw std::invalid_argument(std::string(kCsvWho) + ": extra column '" + e.name + "' has " +
                                  format_number(e.values.size()) +
                                  " values, expected N = " + format_number(N));
    }
    cols.push_back(ColumnRef{e.name, &e.values, 1, 0});
  }
  Impl& w = *impl_;
  std::string& buf = w.buf;

  // header, the first time; the same columns after
  if (w.header.empty()) {
    for (std::size_t c = 0; c < cols.size(); ++c) {
      if (c > 0) buf += ',';
      append_field(buf, cols[c].name);
      w.header.push_back(cols[c].name);
    }
    buf += '\n';
  } else {
    bool same = w.header.size() == cols.size();
    for (std::size_t c = 0; same && c < cols.size(); ++c) same = w.header[c] == cols[c].name;
    if (!same) {
      throw std::invalid_argument(std::string(kCsvWho) + ": '" + w.path +
                                  "': the columns differ from those of the rows written before");
    }
  }

  // one row per sample
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t c = 0; c < cols.size(); ++c) {
      if (c > 0) buf += ',';
      append_number(buf, (*cols[c].field)[i * cols[c].width + cols[c].index]);
    }
    buf += '\n';
    if (buf.size() >= Impl::kFlushAt) w.flush();
  }
  rows_ += Index(N);
}

void CsvWriter::commit() {
  Impl& w = *impl_;
  w.flush();
  // fclose writes what stdio still holds: its failure (a full disk) is a write error too
  errno = 0;
  if (std::fclose(w.file.release()) != 0) {
    detail::throw_io_error(kCsvWho, w.path, "write", errno);
  }
  w.out.commit();
}

bool CsvWriter::keep_partial() noexcept {
  Impl& w = *impl_;
  // (what stdio still holds is dropped with the buffer: writing it failed, or would)
  w.buf.clear();
  if (w.file) std::fclose(w.file.release());
  try {
    w.out.commit();
    return true;
  } catch (...) {
    return false;
  }
}

void write_csv(const Trajectory& traj, const std::string& path,
               const std::vector<CsvColumn>& extra) {
  traj.check_consistent(kCsvWho);
  for (const CsvColumn& e : extra) {
    if (e.values.size() != traj.t.size()) {
      throw std::invalid_argument(std::string(kCsvWho) + ": extra column '" + e.name + "' has " +
                                  format_number(e.values.size()) +
                                  " values, expected N = " + format_number(traj.t.size()));
    }
  }
  CsvWriter out(path);
  out.append(traj, extra);
  out.commit();
}

}  // namespace ukdyn
