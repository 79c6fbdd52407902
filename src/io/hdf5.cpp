// SPDX-License-Identifier: BSD-3-Clause
// HDF5 writer and reader of trajectories (HDF5 C++ API): one dataset per field, names and
// statistics as attributes; written under a temporary name and renamed when complete.
#include "ukdyn/io/trajectory_files.hpp"

#include <H5Cpp.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/atomic_file.hpp"

namespace ukdyn {
namespace {

// The text of an HDF5 exception, with the system's reason when the failure left one in errno
// (a missing directory, no permission, a full disk).
std::string describe(const H5::Exception& e, int err) {
  std::string text = e.getFuncName() + ": " + e.getDetailMsg();
  if (err != 0) text += std::string(" (") + std::strerror(err) + ")";
  return text;
}

// A variable-length UTF-8 string type.
H5::StrType string_type() {
  H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
  type.setCset(H5T_CSET_UTF8);
  return type;
}

// Attribute `name` of `where` holding one string.
void write_string_attribute(H5::H5Object& where, const char* name, const std::string& value) {
  const H5::StrType type = string_type();
  H5::Attribute attr = where.createAttribute(name, type, H5::DataSpace(H5S_SCALAR));
  attr.write(type, value);
}

// Attribute `name` of `where` holding a 1-D array of strings.
void write_strings_attribute(H5::H5Object& where, const char* name,
                             const std::vector<std::string>& values) {
  const H5::StrType type = string_type();
  const hsize_t dims[1] = {hsize_t(values.size())};
  std::vector<const char*> ptrs;
  ptrs.reserve(values.size());
  for (const auto& v : values) ptrs.push_back(v.c_str());
  H5::Attribute attr = where.createAttribute(name, type, H5::DataSpace(1, dims));
  if (!ptrs.empty()) attr.write(type, ptrs.data());
}

// Scalar attribute `name` of `where` (double or 64-bit integer).
void write_scalar_attribute(H5::H5Object& where, const char* name, double value) {
  H5::Attribute attr =
      where.createAttribute(name, H5::PredType::IEEE_F64LE, H5::DataSpace(H5S_SCALAR));
  attr.write(H5::PredType::NATIVE_DOUBLE, &value);
}
void write_scalar_attribute(H5::H5Object& where, const char* name, long value) {
  const std::int64_t v = value;
  H5::Attribute attr =
      where.createAttribute(name, H5::PredType::STD_I64LE, H5::DataSpace(H5S_SCALAR));
  attr.write(H5::PredType::NATIVE_INT64, &v);
}

// Dataset `name` of the N × width field f (1-D of length N when vector is true), stored as it is
// in memory (row i = sample i), chunked by up to 1024 samples and about 1 MiB, shuffled and
// deflated (level 4) when the filters are available.
void write_field(H5::H5File& file, const char* name, const std::vector<double>& f, std::size_t N,
                 std::size_t width, bool vector) {
  const int rank = vector ? 1 : 2;
  const hsize_t dims[2] = {hsize_t(N), hsize_t(width)};
  H5::DataSpace space(rank, dims);

  // chunked and compressed, unless the dataset is empty (chunks must not be)
  H5::DSetCreatPropList props;
  if (N > 0 && width > 0) {
    constexpr std::size_t kMaxChunkSamples = 1024, kMaxChunkBytes = std::size_t(1) << 20;
    const std::size_t samples =
        std::clamp<std::size_t>(kMaxChunkBytes / (width * sizeof(double)), 1, kMaxChunkSamples);
    const hsize_t chunk[2] = {hsize_t(std::min(N, samples)), hsize_t(width)};
    props.setChunk(rank, chunk);
    if (H5Zfilter_avail(H5Z_FILTER_SHUFFLE) > 0) props.setShuffle();
    if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) props.setDeflate(4);
  }

  H5::DataSet ds = file.createDataSet(name, H5::PredType::IEEE_F64LE, space, props);
  if (!f.empty()) ds.write(f.data(), H5::PredType::NATIVE_DOUBLE);
}

// Writes the HDF5 file `path` whole or not at all. The file is built in memory (HDF5's core
// driver without a backing store) by body(file, stage) — `stage` says what it is doing, for the
// error message — and its image is then written by an AtomicFile: a temporary beside `path`
// (mkostemp) renamed over it when complete. HDF5 itself never writes to disk, so a full disk
// or a file-size limit is the plain write error of the image ("No space left on device"),
// never a failure inside HDF5's own close path (which crashed in H5Fclose), and no name is
// opened twice. Memory: the image, about the size of the file.
template <class Body>
void write_whole_file(const std::string& path, const char* who, Body&& body) {
  H5::Exception::dontPrint();
  std::vector<char> image;
  std::string stage = "create the file";
  try {
    // core driver: memory grows by 1 MiB at a time; no backing store, nothing on disk
    H5::FileAccPropList access;
    access.setCore(std::size_t(1) << 20, false);
    H5::H5File file(path, H5F_ACC_TRUNC, H5::FileCreatPropList::DEFAULT, access);
    body(file, stage);
    // the image of the complete file
    stage = "close the file";
    file.flush(H5F_SCOPE_GLOBAL);
    const ssize_t size = H5Fget_file_image(file.getId(), nullptr, 0);
    if (size > 0) {
      image.resize(std::size_t(size));
      if (H5Fget_file_image(file.getId(), image.data(), image.size()) != size) image.clear();
    }
    file.close();
  } catch (const H5::Exception& e) {
    throw std::runtime_error(std::string(who) + ": cannot " + stage + " in '" + path +
                             "': " + describe(e, 0));
  }
  if (image.empty()) {
    throw std::runtime_error(std::string(who) + ": cannot close the file in '" + path +
                             "': HDF5 gave no file image");
  }

  // the image, whole or not at all
  detail::write_whole_file(path, who, image.data(), image.size());
}

}  // namespace

void write_hdf5(const Trajectory& traj, const std::string& path) {
  constexpr const char* kWho = "ukdyn::write_hdf5";
  traj.check_consistent(kWho);
  const std::size_t N = traj.t.size();
  const std::size_t n = std::size_t(traj.n), m = std::size_t(traj.m);
  const std::size_t K = traj.constraint_names.size();

  write_whole_file(path, kWho, [&](H5::H5File& file, std::string& stage) {
    // one dataset per field
    struct Field {
      const char* name;
      const std::vector<double>& values;
      std::size_t width;
      bool vector;
    };
    const Field fields[] = {
        {"t", traj.t, 1, true},
        {"q", traj.q, n, false},
        {"q_dot", traj.qd, n, false},
        {"q_ddot", traj.qdd, n, false},
        {"Qc_ideal", traj.Qc_ideal, n, false},
        {"Qc_nonideal", traj.Qc_nonideal, n, false},
        {"lambda", traj.lambda, m, false},
        {"position_violation", traj.position_violation, K, false},
        {"velocity_violation", traj.velocity_violation, K, false},
        {"kinetic_energy", traj.kinetic_energy, 1, true},
        {"potential_energy", traj.potential_energy, 1, true},
        {"energy", traj.energy, 1, true},
        {"work_nonideal", traj.work_nonideal, 1, true},
        {"work_ideal", traj.work_ideal, 1, true},
        {"work_drive", traj.work_drive, 1, true},
        {"work_external", traj.work_external, 1, true},
        {"work_control", traj.work_control, 1, true},
        {"energy_balance_residual", traj.energy_balance_residual, 1, true},
    };
    for (const Field& f : fields) {
      stage = std::string("write dataset '") + f.name + "'";
      write_field(file, f.name, f.values, N, f.width, f.vector);
    }
    if (!traj.work_impact.empty()) {  // (unilateral contacts, docs/contact.md)
      stage = "write dataset 'work_impact'";
      write_field(file, "work_impact", traj.work_impact, N, 1, true);
    }
    if (!traj.unilateral.empty()) {  // their whole multipliers, by unilateral constraint
      stage = "write dataset 'lambda_total'";
      write_field(file, "lambda_total", traj.lambda_total, N, traj.unilateral.size(), false);
      std::vector<std::string> names;
      for (Index k : traj.unilateral) names.push_back(traj.constraint_names[std::size_t(k)]);
      write_strings_attribute(file, "unilateral_names", names);
    }

    // names, rows and kinds (so that the columns of lambda and the violations can be told apart)
    stage = "write the name attributes";
    write_strings_attribute(file, "coordinate_names", traj.coordinate_names);
    write_strings_attribute(file, "constraint_names", traj.constraint_names);
    std::vector<std::string> kinds;
    for (ConstraintKind kind : traj.constraint_kinds) kinds.emplace_back(to_string(kind));
    write_strings_attribute(file, "constraint_kinds", kinds);
    {
      const std::vector<std::int64_t> rows(traj.constraint_rows.begin(),
                                           traj.constraint_rows.end());
      const hsize_t dims[1] = {hsize_t(K)};
      H5::Attribute attr =
          file.createAttribute("constraint_rows", H5::PredType::STD_I64LE, H5::DataSpace(1, dims));
      if (!rows.empty()) attr.write(H5::PredType::NATIVE_INT64, rows.data());
    }

    // statistics of the run
    stage = "write the statistics attributes";
    const RunStatistics& s = traj.stats;
    write_string_attribute(file, "status", to_string(s.status));
    write_string_attribute(file, "message", s.message);
    write_scalar_attribute(file, "steps", s.steps);
    write_scalar_attribute(file, "rejected_steps", s.rejected_steps);
    write_scalar_attribute(file, "evaluations", s.evaluations);
    write_scalar_attribute(file, "least_squares", s.least_squares);
    write_scalar_attribute(file, "projections", s.projections);
    write_scalar_attribute(file, "wall_time", s.wall_time);
    write_scalar_attribute(file, "max_position_violation", s.max_position_violation);
    write_scalar_attribute(file, "max_velocity_violation", s.max_velocity_violation);
    write_scalar_attribute(file, "energy_balance", s.energy_balance);
    write_scalar_attribute(file, "energy_exchanged", s.energy_exchanged);
    write_scalar_attribute(file, "energy_drift", s.energy_drift);
    write_scalar_attribute(file, "t_reached", s.t_reached);
  });
}

void write_table_hdf5(const std::string& path, const std::vector<CsvColumn>& columns,
                      const std::string& summary) {
  constexpr const char* kWho = "ukdyn::write_table_hdf5";
  const std::size_t N = columns.empty() ? 0 : columns.front().values.size();
  for (const CsvColumn& c : columns) {
    if (c.values.size() != N) {
      throw std::invalid_argument(std::string(kWho) + ": column '" + c.name + "' has " +
                                  std::to_string(c.values.size()) + " values, the first " +
                                  std::to_string(N));
    }
  }
  // the summary's top-level numbers, booleans and strings become attributes of their own
  nlohmann::json j;
  if (!summary.empty()) {
    j = nlohmann::json::parse(summary, nullptr, false);
    if (j.is_discarded() || !j.is_object()) {
      throw std::invalid_argument(std::string(kWho) + ": the summary is not a JSON object");
    }
  }

  write_whole_file(path, kWho, [&](H5::H5File& file, std::string& stage) {
    // one dataset per column, named as in the CSV ('/' would open a group: written '|'); a name
    // met twice gets "#2", "#3"
    std::vector<std::string> names;
    std::set<std::string> used;
    for (const CsvColumn& c : columns) {
      std::string name = c.name.empty() ? "column" : c.name;
      std::replace(name.begin(), name.end(), '/', '|');
      if (name == ".") name = "|";
      const std::string base = name;
      for (int k = 2; !used.insert(name).second; ++k) name = base + "#" + std::to_string(k);
      stage = "write dataset '" + name + "'";
      write_field(file, name.c_str(), c.values, N, 1, true);
      names.push_back(name);
    }
    stage = "write the attributes";
    write_strings_attribute(file, "columns", names);
    if (!summary.empty()) {
      write_string_attribute(file, "summary", summary);
      for (const auto& [key, v] : j.items()) {
        if (key == "columns" || key == "summary") continue;
        if (v.is_boolean()) {
          write_scalar_attribute(file, key.c_str(), long(v.get<bool>()));
        } else if (v.is_number_integer()) {
          write_scalar_attribute(file, key.c_str(), long(v.get<std::int64_t>()));
        } else if (v.is_number()) {
          write_scalar_attribute(file, key.c_str(), v.get<double>());
        } else if (v.is_string()) {
          write_string_attribute(file, key.c_str(), v.get<std::string>());
        }
      }
    }
  });
}

std::string read_hdf5_string_attribute(const std::string& path, const std::string& name) {
  constexpr const char* kWho = "ukdyn::read_hdf5_string_attribute";
  H5::Exception::dontPrint();
  try {
    H5::H5File file(path, H5F_ACC_RDONLY);
    if (!file.attrExists(name)) {
      throw std::runtime_error(std::string(kWho) + ": no attribute '" + name + "' in '" + path +
                               "'");
    }
    H5::Attribute attr = file.openAttribute(name);
    std::string value;
    attr.read(attr.getStrType(), value);
    return value;
  } catch (const H5::Exception& e) {
    throw std::runtime_error(std::string(kWho) + ": cannot read attribute '" + name + "' of '" +
                             path + "': " + describe(e, errno));
  }
}

std::vector<CsvColumn> read_table_hdf5(const std::string& path) {
  constexpr const char* kWho = "ukdyn::read_table_hdf5";
  H5::Exception::dontPrint();
  std::vector<std::string> names;
  try {
    H5::H5File file(path, H5F_ACC_RDONLY);
    if (!file.attrExists("columns")) {
      throw std::runtime_error(std::string(kWho) + ": '" + path +
                               "' has no attribute 'columns' (not written by write_table_hdf5)");
    }
    H5::Attribute attr = file.openAttribute("columns");
    const hssize_t count = attr.getSpace().getSimpleExtentNpoints();
    std::vector<char*> ptrs(std::size_t(std::max<hssize_t>(count, 0)), nullptr);
    const H5::StrType type = string_type();
    if (!ptrs.empty()) attr.read(type, ptrs.data());
    for (char* p : ptrs) names.emplace_back(p ? p : "");
    if (!ptrs.empty()) {
      H5Dvlen_reclaim(type.getId(), attr.getSpace().getId(), H5P_DEFAULT, ptrs.data());
    }
  } catch (const H5::Exception& e) {
    throw std::runtime_error(std::string(kWho) + ": cannot read the columns of '" + path +
                             "': " + describe(e, errno));
  }
  std::vector<CsvColumn> columns;
  columns.reserve(names.size());
  for (const std::string& name : names) columns.push_back({name, read_hdf5_field(path, name)});
  return columns;
}

std::vector<double> read_hdf5_field(const std::string& path, const std::string& dataset) {
  constexpr const char* kWho = "ukdyn::read_hdf5_field";
  H5::Exception::dontPrint();
  errno = 0;
  try {
    H5::H5File file;
    try {
      file.openFile(path, H5F_ACC_RDONLY);
    } catch (const H5::Exception& e) {
      throw std::runtime_error(std::string(kWho) + ": cannot open '" + path +
                               "': " + describe(e, errno));
    }

    // the dataset, with a plain message when it is not there
    if (dataset.empty() || H5Lexists(file.getId(), dataset.c_str(), H5P_DEFAULT) <= 0) {
      throw std::runtime_error(std::string(kWho) + ": no dataset '" + dataset + "' in '" + path +
                               "'");
    }
    H5::DataSet ds = file.openDataSet(dataset);
    if (ds.getTypeClass() != H5T_FLOAT && ds.getTypeClass() != H5T_INTEGER) {
      throw std::runtime_error(std::string(kWho) + ": dataset '" + dataset + "' in '" + path +
                               "' is not numeric");
    }

    // all values, row after row (HDF5 stores row-major, as Trajectory does)
    const H5::DataSpace space = ds.getSpace();
    const hssize_t count = space.getSimpleExtentNpoints();
    std::vector<double> values(std::size_t(std::max<hssize_t>(count, 0)));
    if (!values.empty()) ds.read(values.data(), H5::PredType::NATIVE_DOUBLE);
    return values;
  } catch (const H5::Exception& e) {
    throw std::runtime_error(std::string(kWho) + ": cannot read dataset '" + dataset + "' of '" +
                             path + "': " + describe(e, 0));
  }
}

}  // namespace ukdyn
