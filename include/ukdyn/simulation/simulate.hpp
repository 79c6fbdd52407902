// SPDX-License-Identifier: BSD-3-Clause
/// @file simulation/simulate.hpp
/// Simulation over time: integrate the fundamental equation from an initial state, with drift
/// control, switching at constraint intervals, and a trajectory of everything a user needs to
/// trust the result.
///
/// The integrated state is x = [q; q'; W], W the work channels of the energy balance: the work of
/// the non-ideal constraint forces (dW/dt = q'ᵀ Qc_nonideal), of the ideal ones (non-zero when
/// constraints depend on t), of drives (constraints marked as drives) and of the external forces
/// (System::external_power), each only when the system has such forces (docs/simulation.md,
/// "Energy balance"). Integrators come from Boost.Odeint (RK4, Dormand–Prince 5(4),
/// Runge–Kutta–Fehlberg 7(8)) and SUNDIALS CVODE (BDF); ukdyn writes no step-size control of its
/// own. Output times are reached by dense output (Dormand–Prince, BDF), by landing on them
/// exactly (Fehlberg), or by cubic Hermite interpolation between fixed steps (RK4); a sample is
/// then projected onto the constraints (with projection drift control) and evaluated, so its
/// forces, violations and energy are those of a consistent state.
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/status.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/core/units.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {

/// The integration method.
enum class Integrator {
  kRK4,  ///< classical Runge–Kutta, fixed step SimulationOptions::step
  /// Dormand–Prince's 5th-order formula (the propagated solution of dopri5, 6 stages) at the
  /// fixed step SimulationOptions::step, without error estimate or step control: 1.5× the
  /// evaluations of kRK4 per step, error O(h⁵) instead of O(h⁴) (docs/simulation.md)
  kRK5,
  kDopri5,  ///< Dormand–Prince 5(4), adaptive, dense output (the default)
  kRKF78,   ///< Runge–Kutta–Fehlberg 7(8), adaptive, for reference accuracy
  kBDF,     ///< SUNDIALS CVODE, variable-order BDF with Newton iteration, for stiff problems
};

/// Short name ("rk4", "rk5", "dopri5", "rkf78", "bdf"). Cost O(1).
const char* to_string(Integrator integrator);
/// The integrator of that short name. @throws std::invalid_argument listing the names.
Integrator integrator_from_string(const std::string& name);

/// How constraint drift is controlled.
enum class DriftControl {
  kNone,        ///< integrate A q'' = b as it is
  kBaumgarte,   ///< impose phi'' + 2 alpha phi' + beta² phi = 0 (see Constraint::stabilize)
  kProjection,  ///< project q and q' onto the constraints after every accepted step (default)
};

/// Short name ("none", "baumgarte", "projection"). Cost O(1).
const char* to_string(DriftControl drift);
/// The drift control of that short name. @throws std::invalid_argument listing the names.
DriftControl drift_from_string(const std::string& name);

/// Per-constraint drift control (overrides SimulationOptions::drift for that constraint).
struct ConstraintDrift {
  DriftControl method = DriftControl::kProjection;  ///< the method
  double alpha = 0.0;  ///< Baumgarte gain alpha (1/s) when method is kBaumgarte (0: default)
  double beta = 0.0;   ///< Baumgarte gain beta (1/s) when method is kBaumgarte (0: default)
};

struct Trajectory;

/// What SimulationOptions::progress receives after every accepted step.
struct ProgressReport {
  double t = 0.0;     ///< time reached
  double step = 0.0;  ///< size of the last step (with BDF: of the last converged step attempt)
  long steps = 0;  ///< steps so far (with BDF, converged attempts: the error test may reject some)
  Integrator integrator = Integrator::kDopri5;  ///< the method taking the steps now (kBDF after
                                                ///< a stiffness switch)
};

/// Settings of a simulation. Defaults give constraint violations below 1e-10 on the test
/// problems without the user touching anything.
struct SimulationOptions {
  double t_start = 0.0;                         ///< initial time
  double t_end = 1.0;                           ///< final time (> t_start)
  Integrator integrator = Integrator::kDopri5;  ///< method
  double step = 1e-3;  ///< RK4, RK5: the step; dopri5, rkf78: the first step tried
                       ///< (BDF estimates its own)
  /// Relative and absolute tolerances of the adaptive methods; any rtol down to 1e-12 works,
  /// through singular configurations too (docs/simulation.md, "Singular configurations").
  /// An rtol below kMinimumRtol (the roundoff of double) is raised to it, with a note in
  /// RunStatistics::notes, as CVODE does with tolerances it cannot meet.
  double rtol = 1e-9;
  /// Absolute tolerance of the adaptive methods, in the units of q on q, and on q' times the
  /// run's rate decade min(1, 10^⌊log10(v / ℓ)⌋) (Workspace::rate_unit; 1 for rates of 1 per
  /// unit time and above; docs/simulation.md, "Scales and tolerances"); see rtol.
  double atol = 1e-11;
  double max_step = 0.0;  ///< largest step of adaptive methods (0: unlimited)
  /// Give up after this many accepted steps in the whole run, with every method: the adaptive
  /// methods stop there (Status::kIntegratorFailure, the message says how to raise it); a
  /// fixed-step run (kRK4, kRK5) that would need more is refused before it starts (SettingError).
  /// Model files: simulate: max_steps; command line: --max-steps; Python: max_steps=.
  long max_steps = 10'000'000;
  /// kDopri5 only: when Hairer and Wanner's stiffness test fires (h·ρ > 3.25 at 15 accepted
  /// steps, ρ the dominant eigenvalue of the Jacobian estimated from the last two stages), go
  /// on with kBDF for the rest of the segment — up to the next breakpoint or stick/slip event,
  /// after which dopri5 starts again. A problem that is not stiff never switches, and its
  /// trajectory is bit for bit that of plain dopri5. false: dopri5 throughout, however slow
  /// (docs/simulation.md, "Stiffness").
  bool stiff_switch = true;
  /// Locate the sign changes of the system's switching functions (System::switch_count: the
  /// non-smooth calls of a model file's sign, abs, heaviside, min, max and if) as events: the
  /// step that crosses one stops there and the method restarts on the other side, so every
  /// method keeps its order across the switch (docs/simulation.md, "Switch events"). 1000
  /// switch events, or 1000 accepted steps after one, within 1e-6 of the run's time span (a
  /// sliding mode) end the run as chattering (Status::kIntegratorFailure, the message names the
  /// switch). false: the switches are stepped across (the adaptive methods shrink
  /// their steps there; rk4 and rk5 lose their order). A system without switching functions
  /// pays nothing either way.
  bool switch_events = true;

  double output_every = 0.01;       ///< sample spacing (0: only t_start and t_end)
  std::vector<double> output_at;    ///< further sample times (merged, sorted)
  std::vector<double> breakpoints;  ///< times where the dynamics jumps (C switching, …); the
                                    ///< ends of constraint intervals are added automatically

  DriftControl drift = DriftControl::kProjection;  ///< for every constraint, unless overridden
  std::map<std::string, ConstraintDrift> drift_per_constraint;  ///< overrides, by name
  double baumgarte_alpha = 10.0;  ///< default gain alpha of kBaumgarte (1/s)
  double baumgarte_beta = 10.0;   ///< default gain beta of kBaumgarte (1/s)
  ProjectionOptions projection;   ///< tolerance and iterations of kProjection

  /// Initial state: checked against every constraint (position and velocity level, tolerance
  /// initial_tolerance); when inconsistent, projected if project_initial, else an error naming
  /// the constraints.
  bool project_initial = false;
  /// Largest violation of the initial state (|phi|, and |phi'| or |psi|) accepted as consistent;
  /// see project_initial.
  double initial_tolerance = 1e-10;

  SolverOptions solver;  ///< settings of the fundamental-equation solver

  /// A run that reaches t_end with RunStatistics::energy_balance above this ends with
  /// Status::kEnergyBalance (a warning: the samples are complete) instead of kOk, when the
  /// system accounts for its forces' work (System::accounts_for_energy; otherwise the balance
  /// is reported, not checked). The default
  /// leaves room for the error of the default tolerances on long runs and catches lost energy
  /// (a jump of the state, forces in Q that V does not describe and no external power
  /// declares). Must be > 0; infinity turns the check off. The adaptive methods check against
  /// max(energy_balance_tolerance, 1000 · rtol) (checked_energy_balance_tolerance): a run at a
  /// loose rtol cannot certify the balance below its own error.
  double energy_balance_tolerance = 1e-6;

  /// Called after every accepted step (for progress bars and logs); may be empty.
  std::function<void(const ProgressReport&)> progress;

  /// Where the samples go, one call per sample in time order, each as a Trajectory holding
  /// exactly that sample (names and sizes filled, samples() == 1, energy_balance_residual
  /// included, stats empty; the reference is valid during the call only). Empty (the default):
  /// simulate() keeps every sample in the Trajectory it returns. Set: the returned Trajectory
  /// holds no sample, only the names and the statistics (RunStatistics::samples counts the
  /// calls; energy balance and violations are computed as the samples go), so memory does not
  /// grow with the run's length, and the grid may have up to kMaxStreamedSamples samples
  /// (docs/simulation.md, "Sample grid and streaming"). Called from the thread running
  /// simulate(); an exception it throws stops the run and propagates out of simulate() (the
  /// samples it received before stay received).
  std::function<void(const Trajectory& sample)> sample_sink;

  /// A request to stop (Ctrl-C, a deadline, a GUI's stop button); may be empty. Called after
  /// every accepted step, from the thread running simulate(); once it has returned true the run
  /// stops within a step: at the next sample time if one falls inside the step under way, else
  /// at the step's end, where a last sample is recorded. The run then ends with
  /// Status::kInterrupted, RunStatistics::t_reached the time of that last sample, and every
  /// sample before it as an uninterrupted run has it (docs/simulation.md, "Interrupts and
  /// outputs"). It is not called again after it returned true. Must be cheap (it runs once a
  /// step) and must not throw; the command line sets it from SIGINT and SIGTERM, the Python
  /// module from Python's signal handlers.
  std::function<bool()> should_stop;

  /// The units the run's messages label their numbers with (RunStatistics::message and notes:
  /// the time of a collapsed step, the energy balance's residual): the model's, which a model
  /// file's `units:` sets (Model::options, run_model; docs/model-format.md, "Units"); SI (s, J)
  /// by default. Labels, and one number: the time unit sets the integrators' rate unit on q'
  /// of a run that starts at q = 0 (1 per second in it, at most 1: docs/simulation.md, "The
  /// integrators' atol").
  UnitSystem units;

  /// The coordinates that are angles (n entries, or empty: every
  /// coordinate a length, as a System built in C++ has always been run). The run's violation
  /// scales (set_run_scales) weigh column j of each constraint row a_i by the coordinate's own
  /// scale s_j — ℓ_q = max |q_j| over the length coordinates for a length, 1 (rad) for these —
  /// as phi_scale_i = class(‖a_i ∘ s‖) and phi_dot_scale_i = class(‖a_i ∘ s‖ v_q / ℓ_q), v_q the
  /// lengths' speed scale (an angle's: v_q / ℓ_q), so that a row mixing both, as a ladder's floor
  /// (0, 1, −(L/2) cos θ) in (x, y, θ), is held to the same relative violation in metres and
  /// millimetres (as all lengths, the column of mm per rad was weighed by ℓ in mm: 1000 times
  /// looser, u24 07; docs/simulation.md, "Scales and tolerances"). A model file sets it from its
  /// coordinates' units (Model::coordinate_units: rad, deg — UnitSystem::is_angle —, a planar
  /// body's angle, a revolute joint's; not a quaternion's components, "Scales and tolerances"
  /// says why), and run_model always takes the model's (as its units). Cost: none per step (read
  /// once, at the start of the run, O(m n)).
  /// @throws std::invalid_argument from simulate() when neither empty nor of n entries.
  std::vector<bool> angle_coordinates;
};

/// The most samples a run's grid (t_start, every output_every, output_at, t_end) may have when
/// its samples go to SimulationOptions::sample_sink: 10⁹. A larger grid is refused at the start
/// (std::invalid_argument naming output_every, t_start, t_end, the count and this bound).
inline constexpr double kMaxStreamedSamples = 1e9;

/// The most values a run kept in memory (no sample_sink) may store: 2²⁸ doubles (2 GiB), i.e.
/// at most kMaxStoredValues / (1 + 5n + m + 2K + 9) samples (the values of one sample: t, q,
/// q', q'', Qc_ideal, Qc_nonideal, lambda, two violations per constraint, energies and works);
/// a larger grid is refused at the start like one above kMaxStreamedSamples.
inline constexpr double kMaxStoredValues = 268435456.0;

/// The smallest rtol a run uses: 100 ε ≈ 2.2e-14 (ε the machine epsilon of double). Below it the
/// error estimates are roundoff; a smaller SimulationOptions::rtol is raised to this with a note.
inline constexpr double kMinimumRtol = 100.0 * std::numeric_limits<double>::epsilon();

/// A setting of SimulationOptions that a run cannot use (misuse, the first tier of errors): a
/// std::invalid_argument whose what() names the setting, its value and the rule it breaks, and
/// whose setting() is the setting's name as SimulationOptions spells it ("t_end", "step",
/// "max_steps", "output_at", "output_every", "rtol", …), so that front ends can point at the
/// model file's key or the command-line flag that gave it.
class SettingError : public std::invalid_argument {
 public:
  /// @param setting the name of the setting; @param what the full message.
  SettingError(std::string setting, const std::string& what)
      : std::invalid_argument(what), setting_(std::move(setting)) {}
  /// The name of the setting at fault.
  const std::string& setting() const { return setting_; }

 private:
  std::string setting_;
};

/// Checks the settings of a run of sys as simulate() does before it starts, without running it.
/// The rules (docs/simulation.md, "Settings"): t_start and t_end finite, and t_end − t_start >
/// 1e-12 · max(1, |t_start|, |t_end|) (the resolution of the run's times); step, rtol, atol
/// finite and > 0; max_step, output_every finite and >= 0; every output_at time finite and in
/// [t_start, t_end]; max_steps > 0; Baumgarte gains, initial_tolerance and projection.tolerance
/// finite and >= 0 (the tolerance > 0); energy_balance_tolerance > 0. For kRK4 and kRK5 also:
/// step at least 16 ε max(|t_start|, |t_end|) (a step t cannot resolve), output_every (when
/// > 0) at least step (samples closer than the steps would be interpolated), and the steps the
/// run takes (Σ over the segments between breakpoints of ⌈length / step⌉) at most max_steps.
/// Last, the sample grid: at most kMaxStreamedSamples samples when options.sample_sink is set
/// (a streamed run, as `ukdyn run`'s), else at most what kMaxStoredValues allows; and a spacing
/// output_every above the resolution of the sample times (setting "output_every", or
/// "output_at" for too many output_at times without it).
/// @throws SettingError naming the first setting at fault. Cost O(breakpoints + output_at).
void check_settings(const System& sys, const SimulationOptions& options);

/// The message of an exception that simulate() (or check_settings) threw, for a front end's
/// user: what() without the leading "ukdyn::simulate: " that names the C++ function.
std::string user_message(const std::exception& e);

/// The tolerance a run's energy balance is checked against: max(energy_balance_tolerance,
/// 1000 · rtol) for dopri5, rkf78 and BDF, energy_balance_tolerance for the fixed-step methods.
double checked_energy_balance_tolerance(const SimulationOptions& options);

/// Statistics of a run.
struct RunStatistics {
  long steps = 0;           ///< accepted steps
  long rejected_steps = 0;  ///< steps rejected by the error control
  long evaluations = 0;     ///< evaluations of the fundamental equation
  /// evaluations at states off the constraints (Runge–Kutta stages, Newton iterates: a row
  /// violated beyond projection.tolerance) where A q'' = b had no solution because of that
  /// violation (redundant constraints), and the least-squares q'' was used (docs/simulation.md,
  /// "Redundant constraints"); included in evaluations
  long least_squares = 0;
  /// accepted steps of dopri5 and rkf78 whose error estimate passed only without its components
  /// normal to the projected constraints, which the projection after the step removes: the
  /// steps across a singular configuration (docs/simulation.md, "Singular configurations")
  long tangential_steps = 0;
  /// accepted steps of dopri5 and rkf78 that evaluated f at projected stage states, near a
  /// singular configuration (Workspace::rank_margin below 1e-2; docs/simulation.md)
  long projected_stage_steps = 0;
  long projections = 0;  ///< projections that moved the state (with BDF, CVODE
                         ///< projects before its error test, so rejected attempts count)
  /// located events of Coulomb contacts (stops, whether they stick or slide on through
  /// v_rel = 0, slips, the turns after such a pass) and the slips an impact or release causes;
  /// kMaxEvents of them end the run as chattering. contact_events lists each stick and slip
  long events = 0;
  /// sign changes of switching functions located as events (SimulationOptions::switch_events)
  long switch_events = 0;
  /// stops of a Coulomb contact where sticking was refused as not admissible (it would have
  /// removed kinetic energy, or left the constraints without solution): the contact slid on
  long stick_refusals = 0;
  /// impacts, releases and rests of unilateral constraints (Constraint::unilateral,
  /// docs/contact.md), and sticks and slips of Coulomb contacts, in time order (those of one
  /// instant: impacts, releases, then sticks and slips)
  std::vector<ContactEvent> contact_events;
  /// what the run decided on its own, one line each with its time (at most 20): a refused stick
  std::vector<std::string> notes;
  /// switches from dopri5 to BDF because the problem became stiff (SimulationOptions::
  /// stiff_switch), the time of the first (NaN when none), and the steps BDF took after them
  /// (included in steps)
  long stiff_switches = 0;
  /// the time of the first switch from dopri5 to BDF (NaN when none; see stiff_switches)
  double stiff_switch_time = std::numeric_limits<double>::quiet_NaN();
  /// the steps BDF took after the switches (included in steps; see stiff_switches)
  long stiff_steps = 0;
  double wall_time = 0.0;               ///< seconds
  double max_position_violation = 0.0;  ///< largest |phi| seen after a step or at a sample
  double max_velocity_violation = 0.0;  ///< largest |phi'|, |psi| likewise
  /// The energy balance's certificate: max over the samples of |E(t) − E(0) − ΣW(t)| (ΣW the
  /// sum of the work channels, Trajectory::energy_balance_residual) relative to the energy the
  /// run exchanged: max(energy_exchanged, largest kinetic energy, 1e-9 · largest |T| + |V|)
  /// (never a division by zero). NaN when an energy is NaN. Compared with
  /// SimulationOptions::energy_balance_tolerance.
  double energy_balance = 0.0;
  /// The energy exchanged (J): the sum over the work channels of Σ_i |W(t_i) − W(t_{i−1})|.
  double energy_exchanged = 0.0;
  /// Whether energy_balance was checked against the tolerance: false for a system that does
  /// not account for its forces' work (System::accounts_for_energy) and when the tolerance is
  /// infinite.
  bool energy_balance_checked = false;
  /// The older figure: max |E(t) − E(0) − ΣW(t)| relative to max(|E(0)|, largest kinetic
  /// energy, energy_exchanged, 1): relative to the run's energy when that exceeds one unit of
  /// energy (1 J in SI units), and the absolute residual below it, so that a run in which
  /// nothing moves (E(0) = 0, a block at rest) reports its roundoff, never a division by a
  /// vanishing energy. energy_balance is the figure the run is checked by.
  double energy_drift = 0.0;
  double t_reached = 0.0;  ///< last time integrated to
  /// samples recorded: Trajectory::samples() of a run kept in memory, the calls of
  /// SimulationOptions::sample_sink of a streamed one
  long samples = 0;
  Status status = Status::kOk;  ///< kOk, kEnergyBalance (a warning), kInterrupted (stopped
                                ///< by SimulationOptions::should_stop), or why the run
                                ///< stopped early
  std::string message;          ///< describe_status() of a failure, the warning, or where
                                ///< the run was interrupted ("" when ok)
};

/// Everything recorded at the sample times, stored sample after sample (column i of each
/// field's matrix is sample i). The names and sizes of the system come along so that writers
/// need nothing else.
struct Trajectory {
  std::vector<std::string> coordinate_names;     ///< n
  std::vector<std::string> constraint_names;     ///< K
  std::vector<Index> constraint_rows;            ///< K, rows of each constraint
  std::vector<ConstraintKind> constraint_kinds;  ///< K
  Index n = 0;                                   ///< number of coordinates
  Index m = 0;  ///< number of constraint rows (the length of lambda)
  /// The unilateral constraints (indices into constraint_names, increasing; one row each), the
  /// columns of lambda_total.
  std::vector<Index> unilateral;

  std::vector<double> t;            ///< sample times (N)
  std::vector<double> q;            ///< N × n: coordinates
  std::vector<double> qd;           ///< N × n: velocities q'
  std::vector<double> qdd;          ///< N × n: constrained accelerations q''
  std::vector<double> Qc_ideal;     ///< N × n: ideal constraint force Aᵀ lambda, eq. (11)
  std::vector<double> Qc_nonideal;  ///< N × n: non-ideal constraint force, eq. (12)
  /// N × m: minimum-norm multipliers of the ideal force, except on the stick rows of a Coulomb
  /// contact that sticks: there lambda + lambda_nonideal, the whole multiplier whose holding
  /// force the slip is decided by (docs/friction.md §2) — while another contact of the body
  /// slides, the part of its friction this one carries is in lambda_nonideal (so Qc_ideal =
  /// Aᵀ lambda on every other row only)
  std::vector<double> lambda;
  /// N × u (u = unilateral.size()): each unilateral constraint's whole multiplier
  /// lambda + lambda_nonideal — the force its contact pushes with along its gap's gradient (the
  /// normal force for a gap of unit gradient), which decides its release (docs/contact.md);
  /// lambda alone is only the ideal share, and misses what the contact carries of the non-ideal
  /// forces (joint friction, Coulomb friction at other contacts). Empty without unilateral
  /// constraints.
  std::vector<double> lambda_total;
  std::vector<double> position_violation;  ///< N × K: max |phi| of each constraint (0 if none)
  std::vector<double> velocity_violation;  ///< N × K: max |phi'| or |psi| of each constraint
  std::vector<double> kinetic_energy;      ///< N: T = ½ q'ᵀ M q'
  std::vector<double> potential_energy;    ///< N: V (System's potential; 0 when it has none)
  std::vector<double> energy;              ///< N: E = T + V
  // the energy balance (docs/simulation.md): E(t) − E(0) = the sum of these works
  std::vector<double> work_nonideal;  ///< N: work done by Qc_nonideal since t_start
  /// N: work done by Qc_ideal since t_start, without the drives' share: zero (up to the drift)
  /// unless constraints depend on t explicitly
  std::vector<double> work_ideal;
  std::vector<double> work_drive;     ///< N: work done by the drives' share of Qc_ideal
  std::vector<double> work_external;  ///< N: ∫ P_ext dt (System::external_power), else 0
  std::vector<double> work_control;   ///< N: work of a controller (simulate_controlled), else 0
  /// N: the work of the impacts of unilateral constraints since t_start, Σ (T⁺ − T⁻), <= 0 on
  /// fixed surfaces (a moving surface may do work at an impact; docs/contact.md); empty when the
  /// system has none (then it counts as zero)
  std::vector<double> work_impact;
  /// N: E(t) − E(0) − (the sum of the works above): the balance's failure
  std::vector<double> energy_balance_residual;
  RunStatistics stats;  ///< of the whole run

  /// Number of samples N.
  Index samples() const { return Index(t.size()); }
  /// Checks that the names and every field agree with n, m, K and N (a trajectory from
  /// simulate() always does; a hand-made one may not). @throws std::invalid_argument naming
  /// `who` and the offending field. Cost O(K).
  void check_consistent(const char* who) const;
  /// Field f (stored N × width) as a width × N matrix view, column i = sample i.
  static Eigen::Map<const MatrixXd> view(const std::vector<double>& f, Index width) {
    return {f.data(), width, width == 0 ? 0 : Index(f.size()) / width};
  }
};

/// Integrates sys from (q0, qd0) at options.t_start to options.t_end and returns the samples
/// (or, with options.sample_sink, passes them on one by one and returns the statistics).
/// A numerical failure (inconsistent constraints, NaN, a projection that does not converge, the
/// step limit) stops the run: the samples recorded so far are kept and stats.status /
/// stats.message say what happened, where and when. So does a stop requested by
/// options.should_stop (Status::kInterrupted, the last sample at stats.t_reached).
/// @throws SettingError for a setting a run cannot use (check_settings); std::invalid_argument
/// on other misuse: sizes, an unknown
/// constraint in drift_per_constraint, or initial conditions that violate the constraints when
/// project_initial is false (the message names each violated constraint and by how much), and
/// on a sample grid above kMaxStreamedSamples (with a sample_sink) or kMaxStoredValues (in
/// memory), refused before anything is integrated.
Trajectory simulate(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options = {});

/// The energy balance of a trajectory from its energies and work channels: fills
/// traj.energy_balance_residual and traj.stats.energy_balance, energy_exchanged and
/// energy_drift and energy_balance_checked (= tolerance is finite) (see RunStatistics); then,
/// when the status is kOk and energy_balance exceeds
/// `tolerance` (or is NaN), sets Status::kEnergyBalance and a message saying by how much, when
/// and why it may be (in `units`' energy and time). simulate() calls it; call it again after
/// changing a work column
/// (simulate_controlled does, with work_control). @throws std::invalid_argument when traj is
/// not consistent. Cost O(N).
void compute_energy_balance(Trajectory& traj,
                            double tolerance = std::numeric_limits<double>::infinity(),
                            const UnitSystem& units = {});

/// Consistency of a state with each constraint: one line per violated constraint, naming it
/// and giving the position and velocity violation; empty when every row i meets
/// |φ_i| <= tolerance · ‖a_i‖ ℓ and |ψ_i| <= tolerance · ‖a_i‖ v, in the scales a run from this
/// state takes (ℓ the model's length scale, v the speed scale from the state alone — a run also
/// counts ℓ/duration; docs/simulation.md, "Scales and tolerances"). An open unilateral contact
/// (gap > 0) is no violation. Cost: one Workspace, one evaluation of every constraint's rows.
std::vector<std::string> check_initial_conditions(const System& sys,
                                                  const Eigen::Ref<const VectorXd>& q,
                                                  const Eigen::Ref<const VectorXd>& qd, double t,
                                                  double tolerance);

}  // namespace ukdyn
