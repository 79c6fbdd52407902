// SPDX-License-Identifier: BSD-3-Clause
// The model-file reader's internals, shared by the files that read its sections (modelfile/):
//   reader.cpp            the file, parameters, coordinates, the expressions' set and checks,
//                         initial state, settings and outputs
//   reader_dynamics.cpp   the generalized plant: kinetic_energy, potential_energy, mass_matrix,
//                         forces → M, Q and the external power
//   reader_constraints.cpp  constraints: → A and b
//   reader_nonideal.cpp   nonideal: (friction, forces given by C)
//   reader_multibody.cpp  bodies:, joints: and forces: (a multibody model)
//   reader_control.cpp    control: (the controller run_model applies)
//   yaml_structure.cpp    what yaml-cpp's node tree hides (duplicate keys, documents, aliases)
#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ukdyn/control/control.hpp"
#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/modelfile/expression.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::model_reader {

using expr::Expr;
using expr::ExpressionSet;
using expr::Program;

// the keys of a model file
inline const std::vector<std::string> kTopLevelKeys = {
    "name",        "parameters", "coordinates", "kinetic_energy", "potential_energy",
    "mass_matrix", "forces",     "constraints", "nonideal",       "initial",
    "simulate",    "output",     "bodies",      "joints",         "control",
    "visual",      "units",      "robot",       "tables",         "contacts"};

// a table's columns as read (tables:, modelfile/reader_tables.cpp): names in the order given,
// values per column, and per row its CSV line (1-based; 0 for data written in the model file)
struct TableColumns {
  std::vector<std::string> names;
  std::vector<std::vector<double>> values;
  std::vector<int> lines;
};

inline bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// Whether `given` names the coordinate `name`: the same text, or the same once every '.' is
// read as '_' — a body's coordinates are spelled crank.x in the CSV and the C++/Python names,
// crank_x in expressions (a '.' is not an identifier character); both are accepted wherever a
// model file names a coordinate (docs/multibody.md).
inline bool names_coordinate(const std::string& given, const std::string& name) {
  if (given == name) return true;
  if (given.size() != name.size()) return false;
  for (std::size_t i = 0; i < given.size(); ++i) {
    const char a = given[i] == '.' ? '_' : given[i], b = name[i] == '.' ? '_' : name[i];
    if (a != b) return false;
  }
  return true;
}

// a number as a person writes it (2, 0.5, 1e-06): the shortest text that reads back the same
inline std::string brief(double v) { return format_number(v); }

// A program's evaluation with buffers owned by the caller.
struct Evaluator {
  Program program;
  std::vector<double> out, scratch;
  explicit Evaluator(Program p)
      : program(std::move(p)),
        out(std::size_t(program.outputs())),
        scratch(std::size_t(program.scratch_size())) {}
  const double* run(const double* in) {
    program.evaluate(in, out.data(), scratch.data());
    return out.data();
  }
};

// the inputs of every program: [q; q'; t; N_c …; lambda_c …]
struct InputLayout {
  Index n = 0, extra = 0;
  Index size() const { return 2 * n + 1 + extra; }
  // in[0, 2n] = [q; q'; t] (`in` holds at least size() doubles)
  void fill(double* in, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
            double t) const {
    std::copy(q.data(), q.data() + n, in);
    std::copy(qd.data(), qd.data() + n, in + n);
    in[2 * n] = t;
  }
  void fill(std::vector<double>& in, const Eigen::Ref<const VectorXd>& q,
            const Eigen::Ref<const VectorXd>& qd, double t) const {
    fill(in.data(), q, qd, t);
  }
};

// The buffers of a model file's callables M, Q, V, P_ext and C for one workspace (its
// CallableScratch, SystemBuilder::scratch): the input vector [q; q'; t; N_c …; lambda_c …],
// and the outputs and scratch of the largest program. A large model's compiled constraints
// share its input vector too: each writes the inputs its programs read (and only those are
// read), so a model of 10⁴ coordinates and 5000 local constraints fills O(1) inputs per
// constraint and keeps one vector per workspace, not 5000. Every user writes the inputs it
// reads before evaluating (the extra inputs stay 0 for the constraints, which do not read them).
struct ModelBuffers final : CallableScratch {
  std::vector<double> in, out, scratch;
};

// The sizes of a model's ModelBuffers: grown while the reader compiles (fit), read only
// afterwards, when a Workspace makes its scratch (factory).
struct BufferSizes {
  std::size_t inputs = 0, outputs = 0, scratch = 0;
  void fit(Index in, const Program& p) {
    inputs = std::max(inputs, std::size_t(in));
    outputs = std::max(outputs, std::size_t(p.outputs()));
    scratch = std::max(scratch, std::size_t(p.scratch_size()));
  }
  static ScratchFactory factory(std::shared_ptr<const BufferSizes> sizes) {
    return [sizes = std::move(sizes)]() -> std::unique_ptr<CallableScratch> {
      auto b = std::make_unique<ModelBuffers>();
      b->in.assign(sizes->inputs, 0.0);
      b->out.assign(sizes->outputs, 0.0);
      b->scratch.assign(sizes->scratch, 0.0);
      return b;
    };
  }
};

// The buffers of a model file's callable given the workspace's scratch: the model's
// ModelBuffers (SystemBuilder::scratch), or — when it is evaluated without one (System's
// convenience accessors make a scratch per call, so this is only a misuse guard) — a failure.
inline ModelBuffers& model_buffers(CallableScratch* s) { return static_cast<ModelBuffers&>(*s); }

// Evaluates p at the inputs `fill` writes into an input vector of `inputs` values, with buffers
// of this call — for the callables whose signature carries no scratch (a multibody drive or
// applied wrench, a friction's surface velocity, a controller's weight N): on the stack when
// in, out and scratch fit in kLocalDoubles (no allocation: small models), else allocated for the
// call. Thread-safe: nothing is shared. `use` reads the outputs.
inline constexpr std::size_t kLocalDoubles = 2048;
template <class Fill, class Use>
void evaluate_local(const Program& p, Index inputs, Fill&& fill, Use&& use) {
  const std::size_t ni = std::size_t(inputs), no = std::size_t(p.outputs()),
                    ns = std::size_t(p.scratch_size()), total = ni + no + ns;
  double local[kLocalDoubles];
  std::vector<double> heap;
  double* base = local;
  if (total > kLocalDoubles) {
    heap.assign(total, 0.0);
    base = heap.data();
  } else {
    std::fill(local, local + ni, 0.0);
  }
  fill(base);
  p.evaluate(base, base + ni, base + ni + no);
  use(static_cast<const double*>(base + ni));
}

// Inputs of at most this many values are kept by each constraint's scratch; larger ones are
// shared through the workspace's ModelBuffers.
inline constexpr Index kOwnInputsMax = 1024;

// Buffers of one compiled constraint: its outputs and scratch, and its inputs when small.
struct CompiledScratch final : ConstraintScratch {
  // `shared`: the workspace's input vector to use, or null for one of its own
  CompiledScratch(const Program& accel_program, const Program& levels_program, Index size,
                  std::vector<double>* shared)
      : in(shared != nullptr ? 0 : std::size_t(size), 0.0),
        inputs(shared != nullptr ? shared : &in),
        accel(accel_program),
        levels(levels_program) {}
  std::vector<double> in;       // its own inputs (small model), else empty
  std::vector<double>* inputs;  // in, or the workspace's ModelBuffers::in
  Evaluator accel, levels;
};

// A constraint from model-file expressions: one program for [A (row-major); b], one for
// [phi; phi'] (holonomic), [psi] (nonholonomic) or nothing (acceleration form). With `columns`
// (the coordinates A can be non-zero in, strictly increasing, fewer than n) the program's A holds
// those columns only (rows × columns.size()): the model is local, and a large model's sparse
// engine assembles A in O(rows · columns) instead of O(rows · n) (x2k = x2k+1 over 10⁴
// coordinates); empty, A is rows × n (dense rows).
class CompiledConstraint final : public ConstraintModel {
 public:
  // `inputs`: the inputs (indices into [q; q'; t; …]) that accel and levels read, increasing
  CompiledConstraint(ConstraintKind kind, Index rows, Index n, InputLayout layout, Program accel,
                     Program levels, std::vector<Index> inputs, std::vector<Index> columns = {})
      : kind_(kind),
        rows_(rows),
        n_(n),
        layout_(layout),
        accel_(std::move(accel)),
        levels_(std::move(levels)),
        inputs_(std::move(inputs)),
        columns_(std::move(columns)),
        width_(columns_.empty() ? n : Index(columns_.size())) {}

  // own inputs (a small model's, or without the workspace's ModelBuffers)
  std::unique_ptr<ConstraintScratch> make_scratch(Index) const override {
    return std::make_unique<CompiledScratch>(accel_, levels_, layout_.size(), nullptr);
  }
  // a large model's constraints share the workspace's input vector (ModelBuffers)
  std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index n,
                                                          CallableScratch* shared) const override {
    auto* buffers = dynamic_cast<ModelBuffers*>(shared);
    if (layout_.size() <= kOwnInputsMax || buffers == nullptr ||
        buffers->in.size() < std::size_t(layout_.size())) {
      return make_scratch(n);
    }
    return std::make_unique<CompiledScratch>(accel_, levels_, layout_.size(), &buffers->in);
  }

  const std::vector<Index>& columns() const override { return columns_; }

  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    const double* out = evaluate(q, qd, t, s);
    if (columns_.empty()) {
      for (Index r = 0; r < rows_; ++r) {
        for (Index j = 0; j < n_; ++j) A(r, j) = out[r * n_ + j];
      }
    } else {
      A.setZero();
      for (Index r = 0; r < rows_; ++r) {
        for (Index k = 0; k < width_; ++k) A(r, columns_[std::size_t(k)]) = out[r * width_ + k];
      }
    }
    for (Index r = 0; r < rows_; ++r) b[r] = out[rows_ * width_ + r];
  }

  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t, ConstraintScratch* s,
                               Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override {
    const double* out = evaluate(q, qd, t, s);
    for (Index r = 0; r < rows_; ++r) {
      for (Index k = 0; k < width_; ++k) A_local(r, k) = out[r * width_ + k];
      b[r] = out[rows_ * width_ + r];
    }
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    position.setZero();
    velocity.setZero();
    if (kind_ == ConstraintKind::kAcceleration) return;
    auto& w = static_cast<CompiledScratch&>(*s);
    const double* out = w.levels.run(fill(w, q, qd, t));
    if (kind_ == ConstraintKind::kHolonomic) {
      for (Index r = 0; r < rows_; ++r) {
        position[r] = out[r];
        velocity[r] = out[rows_ + r];
      }
    } else {
      for (Index r = 0; r < rows_; ++r) velocity[r] = out[r];
    }
  }

 private:
  // the inputs the programs read, in the scratch's or the workspace's input vector: O(inputs)
  const double* fill(CompiledScratch& w, const Eigen::Ref<const VectorXd>& q,
                     const Eigen::Ref<const VectorXd>& qd, double t) const {
    std::vector<double>& in = *w.inputs;
    for (const Index k : inputs_) {
      in[std::size_t(k)] = k < n_ ? q[k] : k < 2 * n_ ? qd[k - n_] : k == 2 * n_ ? t : 0.0;
    }
    return in.data();
  }
  // [A (rows × width_, row-major); b] at (q, q', t)
  const double* evaluate(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* s) const {
    auto& w = static_cast<CompiledScratch&>(*s);
    return w.accel.run(fill(w, q, qd, t));
  }

  ConstraintKind kind_;
  Index rows_, n_;
  InputLayout layout_;
  Program accel_, levels_;
  std::vector<Index> inputs_;
  std::vector<Index> columns_;
  Index width_;
};

// The node tree of `text` (YAML::Load's, marks included; a null node when the text holds no
// document), read in one pass that also refuses, located, what yaml-cpp's node tree would hide: a
// key given twice in a mapping, a second document, an alias inside the node it names, nesting
// deeper than yaml-cpp or the stack allows; and YAML syntax errors
// (modelfile/yaml_structure.cpp). Cost: O(size of the text). @throws ModelError
YAML::Node load_checked_yaml(const std::string& text, const std::string& file);

// The first velocity (in declaration order) that e depends on, or null: the inputs are
// [q; q'; t; …], so the velocities are the inputs n … 2n − 1 (one traversal of e).
const std::string* velocity_in(const ExpressionSet& set, Expr e,
                               const std::vector<std::string>& velocities);

// When YAML has split an expression of the flow list `list` at the commas inside its
// parentheses: the hint to quote it, with the list as it should be written; else "".
std::string cut_flow_list_hint(const YAML::Node& list, const std::string& key);

// A .urdf path (any case): load_model reads it as the model text urdf_model_text(path),
// `robot: {urdf: '<its file name>'}` (modelfile/reader_urdf.cpp).
bool is_urdf_path(const std::string& path);
std::string urdf_model_text(const std::string& path);

// A file named in the model file `model_file` (a URDF, a table): `path` as written, relative to
// the model file's directory. A built-in example (`model_file` "examples/models/NAME.yaml", its
// text embedded in the program) finds its files in the first examples directory that holds them:
// $UKDYN_EXAMPLES_DIR, the installed one (share/doc/ukdyn/examples/models), the source tree's;
// so `ukdyn run --example leg_four_bar_knee` works from any directory
// (modelfile/example_files.cpp).
std::filesystem::path model_relative_path(const std::string& model_file, const std::string& path);

// The reader: one model file.
class Reader {
 public:
  // `tables`: the tables the caller gives (load_model's), or null; kept by the caller
  Reader(std::string file, const std::map<std::string, double>& overrides,
         const GivenTables* tables = nullptr)
      : file_(std::move(file)), overrides_(overrides), given_tables_(tables) {}

  /// The file's YAML, parsed and checked (not XML, no NUL byte, no duplicate key …: errors
  /// located in `file`). Uses no GiNaC: parse_model runs it outside its lock.
  static YAML::Node load_yaml(const std::string& text, const std::string& file);

  /// The whole file (`root`, from load_yaml): the plant, then its controller (control:).
  Model read(const YAML::Node& root);

 private:
  // the plant (everything but control:); `root` is the parsed file
  Model read_plant(const YAML::Node& root);
  // generalized coordinates: coordinates:, kinetic_energy: / mass_matrix:, forces:, …
  Model read_generalized(const YAML::Node& root);
  // the expression inputs [q; q'; t; N_c …; lambda_c …] over coordinates_ and velocities_,
  // with the parameters (and pi) as constants; `cnames`: the named constraints
  // the names of the constraints: section's entries, each once, in order (a name given twice is
  // refused by read_constraints), for the expression set's constraint functions
  static std::vector<std::string> constraint_names(const YAML::Node& root);
  void make_expression_set(const YAML::Node& root, const std::vector<std::string>& cnames);
  // tables: → the set's table columns (modelfile/reader_tables.cpp); `where` is the file: or
  // data: node, `what` names the table
  void read_tables(const YAML::Node& root);
  TableColumns read_csv(const YAML::Node& where, const std::string& what);
  TableColumns read_hdf5_table(const YAML::Node& where, const YAML::Node& table,
                               const std::string& what);
  // the file named at `where`, relative to the model file's directory; located errors when it is
  // not a regular file or too large
  std::filesystem::path table_path(const YAML::Node& where, const std::string& what);
  TableColumns read_data(const YAML::Node& data, const std::string& what);
  TableColumns given_data(const YAML::Node& table, const TableData& data, const std::string& what);
  // (a value that depends on a --set override says so first: "--set e=1.5: …", overridden_in)
  [[noreturn]] void fail(const YAML::Node& at, const std::string& message,
                         const std::string& hint = "") const {
    const YAML::Mark m = at.Mark();
    throw ModelError(file_, m.line + 1, m.column + 1, overridden_in(at) + message, hint);
  }
  // "--set NAME=VALUE: " for each override (overrides_) the scalar `at` reads, directly or
  // through the parameters derived from it (set_by_); "" for a node that reads none. Cost
  // O(length of the scalar).
  std::string overridden_in(const YAML::Node& at) const;
  // the overrides an expression's text reads, directly or through derived parameters (set_by_),
  // each once, in the order they are read. O(length of the text)
  std::vector<std::string> overrides_read(const std::string& text) const;
  // where a node is in the file (1-based)
  static FilePosition position(const YAML::Node& at) {
    const YAML::Mark m = at.Mark();
    return {m.line + 1, m.column + 1};
  }
  [[noreturn]] void fail_at(const YAML::Mark& m, const std::string& message,
                            const std::string& hint = "") const {
    throw ModelError(file_, m.line + 1, m.column + 1, message, hint);
  }

  double number(const YAML::Node& node, const std::string& what);
  // a coefficient of friction (mu, mu_static): a number in [0, kMaxFrictionCoefficient], else a
  // located error that says the range (reader_nonideal.cpp)
  double friction_coefficient(const YAML::Node& node, const std::string& what);
  Expr expression(const YAML::Node& node, const std::string& what, bool in_C = false);
  Program compile(const std::vector<Expr>& exprs, const YAML::Node& where,
                  const std::string& what) const;
  std::vector<YAML::Node> rows_of(const YAML::Node& node, const std::string& what);
  void read_parameters(const YAML::Node& root);
  // the value of the parameter `name` written as an expression at `node` of the parameters
  // before it (`earlier` holds them as constants; `order` lists every parameter, `index` is
  // this one's place): located errors for a parameter written at or after it, unknown names,
  // and values that are not finite
  double derived_parameter(const YAML::Node& node, const std::string& name, ExpressionSet& earlier,
                           const std::vector<std::string>& order, std::size_t index);
  void read_coordinates(const YAML::Node& root);
  void read_dynamics(const YAML::Node& root, SystemBuilder& builder);
  void read_constraints(const YAML::Node& root, SystemBuilder& builder);
  // one constraint's rows (holonomic:, nonholonomic: or A: with b:) and active:, compiled
  Constraint read_constraint(const YAML::Node& c, const std::string& name, const std::string& what);
  // unilateral: and restitution: of a constraint entry (reader_constraints.cpp, docs/contact.md)
  void read_unilateral(const YAML::Node& c, const std::string& name, Constraint& constraint);
  // restitution: e in [0, 1] (default 0) and restitution_law: newton | poisson of a constraint
  // or contact entry (either node may be absent); errors name `what` ("constraint 'floor'")
  std::pair<double, RestitutionLaw> read_restitution(const YAML::Node& e, const YAML::Node& law,
                                                     const std::string& what);
  void read_nonideal(const YAML::Node& root, SystemBuilder& builder);
  // a Coulomb friction's regularization_velocity when its entry gives none: 1e-9 m/s
  // (CoulombFriction's default) written in the model's units: (length per time unit), so that
  // a model in km, t, min regularizes, and stops its slides, at the speed of the same model in SI
  // (the stop speed is 100 of it: docs/friction.md)
  double default_regularization_velocity(const YAML::Node& root);
  // a coordinate-path Coulomb friction's normal coordinates p (docs/friction.md §1):
  // `normal_coordinates:` when given, else the coordinates whose unit (units: of the file) is
  // the sliding coordinates' (or the model's length unit) or not known; empty when that is all
  // of them. Refuses sliding coordinates of different units.
  std::vector<Index> normal_coordinates(const YAML::Node& root, const YAML::Node& f,
                                        const std::vector<Index>& sliding);
  // after the build: refuses, at the friction's entry, a normal row with no coordinate in p, or
  // one that mixes coordinates of unknown units (a length with an angle?) without
  // normal_coordinates: (then N would mix a force and a torque)
  void check_friction_normals(const YAML::Node& root, const System& sys);
  // a Coulomb friction's surface_velocity: `count` expressions of q and t, compiled with their
  // rates along the motion
  SurfaceVelocityFn surface_velocity(const YAML::Node& node, std::size_t count);
  void read_initial(const YAML::Node& root, Model& model);
  void read_simulate(const YAML::Node& root, Model& model);
  void read_output(const YAML::Node& root, Model& model);
  // visual: and the bodies' visual: entries (modelfile/reader_visual.cpp); the points'
  // expressions are appended to `outputs` (their columns follow the output expressions)
  void read_visual(const YAML::Node& root, Model& model, std::vector<Expr>& outputs);
  // gap.<name>: the gap of each unilateral constraint, an output column (docs/contact.md); the
  // coordinates each gap reads are kept for label_gaps
  void add_gap_outputs(const YAML::Node& root, Model& model, std::vector<Expr>& outputs);
  // the unit of each gap.<name> that add_gap_outputs wrote and units: does not name: the one
  // its coordinates share: mm for yA in mm, rad for a joint limit th − th_min with th in rad;
  // none when they differ, when one of them has no unit, or when it reads none
  void label_gaps(Model& model) const;
  // units: {x: m, theta: rad} (each coordinate's unit, for the plots' labels)
  void read_units(const YAML::Node& root, Model& model);
  // units: {length: mm, mass: g, time: ms} (the base units, from their accepted lists)
  void read_unit_system(const YAML::Node& units_node, UnitSystem& units);
  // the run's units (SimulationOptions::units) from units: (reader.cpp)
  void apply_time_unit(Model& model) const;
  void check_mass_matrix(const YAML::Node& root, const Model& model);
  void check_settings(const YAML::Node& root, Model& model);
  Index coordinate(const YAML::Node& node);

  // ---- multibody models (modelfile/reader_multibody.cpp): bodies:, joints:, forces: --------
  // Builds the plant from the bodies, joints and force elements; sets coordinates_, velocities_
  // (the bodies' coordinates: <body>_x, _y, _theta | _z, _u0 … _u3) and the expression set;
  // fills model.multibody, q0 and qd0 (the bodies' initial poses and velocities).
  Model read_multibody(const YAML::Node& root);
  // the sections' reader (modelfile/reader_multibody.cpp): uses fail, number, expression and
  // compile
  friend class MultibodyReader;

  // ---- robots (modelfile/reader_urdf.cpp): robot: names a URDF ------------------------------
  // The plant from the URDF's tree with the file's torques, loops and constraints; sets
  // coordinates_ (the joints' names), the expression set, model.q0 (neutral) and model.robot.
  Model read_robot(const YAML::Node& root);
  // a control requirement's pose: {link, point, position: [3 expressions of t], orientation:
  // [w, x, y, z] expressions of t} on the robot (tree::pose_requirement)
  Constraint read_pose_requirement(const YAML::Node& r, const std::string& name,
                                   const std::string& what);
  std::shared_ptr<const tree::Tree> robot_;  // the robot read by read_robot (or null)
  // contacts: of a robot model (modelfile/reader_robot_contacts.cpp): one unilateral
  // tree::contact_constraint (disk_contact_constraint) per entry, added to `builder`, and its
  // drawn contact to `drawn`; `names` holds the loops' names and gets the contacts'; `urdf`
  // names the file in errors
  void read_robot_contacts(const YAML::Node& root, const tree::Tree& robot, const std::string& urdf,
                           std::set<std::string>& names, SystemBuilder& builder,
                           std::vector<VisualContact>& drawn);
  // the contacts whose Coulomb friction slides the contact point (a robot's, set by
  // read_robot_contacts), by name: the maker of their ContactKinematics, which read_nonideal
  // calls (std::invalid_argument: not supported, reported at the friction's entry)
  std::map<std::string, std::function<ContactKinematics()>> point_contacts_;

  // ---- control (modelfile/reader_control.cpp): control: ------------------------------------
  // Builds model.controller from the control: section (nothing when absent). With `nominal:` the
  // plant is read again with those parameters for the controller's own model.
  void read_control(const YAML::Node& root, Model& model);
  ErrorDynamics read_error_dynamics(const YAML::Node& r, const std::string& what,
                                    ConstraintKind kind);
  WeightFn read_weight(const YAML::Node& N, bool& constant, MatrixXd& value);

  std::string file_;
  std::map<std::string, double> overrides_;
  const GivenTables* given_tables_ = nullptr;  // the caller's tables (or none)
  std::map<std::string, double> parameters_;
  // each parameter whose value comes from overrides_: the overrides it reads (its own, or those
  // of the parameters its expression reads), by name (read_parameters)
  std::map<std::string, std::vector<std::string>> set_by_;
  std::vector<std::string> coordinates_, velocities_;
  // (gap.<name>, the coordinates its expression reads) of add_gap_outputs, for label_gaps
  std::vector<std::pair<std::string, std::vector<Index>>> gap_reads_;
  // a robot's joints whose URDF names are not identifiers, (name, identifier): "hip-1" is
  // written hip_1 in expressions (read_robot); an expression that holds the name as written
  // is refused (refuse_renamed), as it would read "hip - 1"
  std::vector<std::pair<std::string, std::string>> renamed_;
  void refuse_renamed(const YAML::Node& node, const std::string& what);
  ModelPositions positions_;  // where the file gives what a run may refuse (Model::positions)
  // initial: project: {keep: [...]}: the node, and per coordinate whether its position and its
  // velocity are kept (empty without keep)
  YAML::Node keep_node_;
  std::vector<unsigned char> keep_q_, keep_qd_;
  std::vector<std::string> kept_names_;
  // makes the initial state consistent keeping keep_q_, keep_qd_ (initial_keep.hpp)
  void apply_keep(Model& model);
  // the desired values of the holonomic requirements' rows, as output expressions
  // (desired_<row>: note_desired, added by read_output unless the file declares that name)
  std::vector<std::pair<std::string, Expr>> desired_outputs_;
  void note_desired(const YAML::Node& root);
  std::vector<Expr> declared_kinematics(const YAML::Node& root);
  void note_desired_rows(const YAML::Node& holonomic, const std::string& name,
                         const std::string& what, const std::vector<Expr>& declared);
  std::vector<std::string> constraint_names_;  // in declaration order
  // the coordinate-path Coulomb frictions' entries (read_nonideal), for check_friction_normals
  std::vector<YAML::Node> coulomb_entries_;
  std::vector<std::string> constraint_inputs_;  // N_c and lambda_c of each named constraint
  // the constraints whose N_c and lambda_c are inputs (those named by an identifier), in the
  // order of constraint_inputs_; a subset of constraint_names_
  std::vector<std::string> input_constraints_;
  std::vector<Index> constraint_rows_;
  std::unique_ptr<ExpressionSet> set_;
  InputLayout layout_;
  std::vector<std::pair<std::string, std::string>> chain_;
  // D e, the total time derivative along chain_ (ExpressionSet::total_derivative), and 0 at
  // once when e holds no coordinate and not t (what that call gives then). Each call of the
  // set's compares the chain it is given with the last one, O(n): called once per coordinate
  // (∂T/∂q̇_i of a constant M), it made reading n coordinates O(n²) — 66 s for 10⁵
  Expr time_derivative(Expr e);
  // the sizes of the model's ModelBuffers (the plant's callables')
  std::shared_ptr<BufferSizes> sizes_ = std::make_shared<BufferSizes>();
  // the expressions of the dynamics (M, Q, the constraints' programs, C) whose non-smooth calls
  // are the model's switches (note_switches, add_switches)
  std::vector<Expr> switch_sources_;
  void note_switches(const std::vector<Expr>& exprs) {
    switch_sources_.insert(switch_sources_.end(), exprs.begin(), exprs.end());
  }
  // the constraints' expressions among switch_sources_, by constraint name: a switch of one is a
  // kink of the constraint (its name in System::switch_names says so: see add_switches)
  std::vector<std::pair<std::string, std::vector<Expr>>> constraint_switch_sources_;
  // the switching functions of switch_sources_ that q, q' and t determine, named, compiled into
  // `program` (over layout_); false when there are none. Clears the sources.
  bool switches(std::vector<std::string>& names, Program& program);
  // switches() into the builder's SystemBuilder::switching_functions (none: no callable, so no
  // event hook)
  void add_switches(SystemBuilder& builder);
};

}  // namespace ukdyn::model_reader
