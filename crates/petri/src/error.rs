//! The error type of the crate.

use std::path::PathBuf;

/// Everything that can go wrong when reading, building, exploring or solving a
/// net. User input never panics: it ends up here, with enough context (file
/// position, element name, limit) to fix it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("cannot access {path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// The file is not well-formed XML.
    #[error("{location}: malformed XML: {message}")]
    Xml {
        /// `file:line:column`.
        location: String,
        /// The XML parser's message.
        message: String,
    },
    /// The file is well-formed but does not describe a valid net.
    #[error("{location}: {message}")]
    Format {
        /// Where: `file:line:column` and/or the element.
        location: String,
        /// What is wrong.
        message: String,
    },
    /// The file name does not say which format it is in.
    #[error("cannot tell the format of {path}: use the extension .pnpro, .pnml, .toml (or .dot for output)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// An expression (rate, weight, marking, measure) does not parse.
    #[error("in expression `{text}`, at character {position}: {message}")]
    Expr {
        /// The expression as written.
        text: String,
        /// 1-based character position of the problem.
        position: usize,
        /// What is wrong.
        message: String,
    },
    /// An expression could not be evaluated.
    #[error("cannot evaluate `{text}` for {context}: {message}")]
    Eval {
        /// The expression.
        text: String,
        /// What it belongs to, e.g. "the rate of transition t3".
        context: String,
        /// What is wrong.
        message: String,
    },
    /// Two places, two transitions or a place and a transition share a name.
    #[error("duplicate name `{name}`: {first} and {second} must be named differently")]
    DuplicateName {
        /// The name.
        name: String,
        /// What the first holder of the name is.
        first: &'static str,
        /// What the second holder of the name is.
        second: &'static str,
    },
    /// An arc refers to a node that does not exist (or has the wrong kind).
    #[error("{arc}: unknown {expected} `{name}`{hint}")]
    UnknownNode {
        /// Description of the arc (with its position when known).
        arc: String,
        /// The kind of node that was expected ("place", "transition").
        expected: &'static str,
        /// The name or id that was not found.
        name: String,
        /// `; did you mean `X`?` naming the closest node, or empty
        /// ([`crate::suggest::hint`]).
        hint: String,
    },
    /// A parameter is used but has no value.
    #[error(
        "parameter `{name}` has no value (used by {used_by}); give it one, e.g. --param {name}=VALUE{hint}"
    )]
    UnboundParameter {
        /// The parameter.
        name: String,
        /// The first element using it.
        used_by: String,
        /// Extra help, e.g. a value suggested by the file.
        hint: String,
    },
    /// A value given for a parameter the net does not have.
    #[error("the net has no parameter `{name}` (its parameters: {known})")]
    UnknownParameter {
        /// The name given.
        name: String,
        /// The net's parameters, comma separated.
        known: String,
    },
    /// A command-line style `NAME=VALUE` assignment does not parse.
    #[error("bad parameter assignment `{text}`: {message}")]
    BadAssignment {
        /// The text given.
        text: String,
        /// What is wrong.
        message: String,
    },
    /// A place or transition was named that the net does not have.
    #[error("the net has no {kind} `{name}`")]
    UnknownName {
        /// "place" or "transition".
        kind: &'static str,
        /// The name.
        name: String,
    },
    /// A number is out of its allowed range (a zero weight, a negative rate…).
    #[error("{what} of {element} must be {requirement}, got {value}")]
    InvalidValue {
        /// The element, e.g. "transition `t3`".
        element: String,
        /// Which attribute, e.g. "rate".
        what: &'static str,
        /// The rule, e.g. "a finite number > 0".
        requirement: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A timed transition has no rate and no default was given.
    #[error(
        "timed transition `{transition}` has no rate: give one in the model, or a default for all (--default-rate R)"
    )]
    MissingRate {
        /// The transition.
        transition: String,
    },
    /// State-space generation reached the configured limit.
    #[error(
        "the reachability graph has more than {limit} markings (limit reached after {explored} were fully explored){hint}; raise the limit with --max-states if the net is bounded"
    )]
    StateLimit {
        /// The configured limit.
        limit: usize,
        /// Markings whose successors had all been generated.
        explored: usize,
        /// Diagnosis, e.g. places whose token counts keep growing.
        hint: String,
    },
    /// The state space would need more memory than allowed (see
    /// [`crate::ExploreParams::max_memory`]): generation stopped before
    /// allocating it.
    #[error(
        "the state space needs more memory than the limit: about {} to generate, compile and solve the {markings} markings and {edges} edges found so far, against a limit of {} (by default 85 % of the memory available when generation started); raise it with --max-memory if the machine has more free memory",
        crate::error::format_bytes(*.estimate),
        crate::error::format_bytes(*.limit)
    )]
    MemoryLimit {
        /// Estimated bytes for what was found so far.
        estimate: u64,
        /// The limit in bytes.
        limit: u64,
        /// Markings found so far.
        markings: usize,
        /// Edges found so far.
        edges: usize,
    },
    /// A place's token count does not fit the engine's counters.
    #[error("place `{place}` would hold more than {limit} tokens")]
    TokenOverflow {
        /// The place.
        place: String,
        /// The largest count supported.
        limit: u64,
    },
    /// A set of vanishing markings from which no tangible marking is reachable.
    #[error(
        "timeless trap: {count} vanishing marking(s) fire immediate transitions forever without reaching a tangible marking, e.g. {markings}"
    )]
    TimelessTrap {
        /// How many markings form the trap.
        count: usize,
        /// A few of them, printed.
        markings: String,
    },
    /// An iterative solver stopped before reaching its tolerance.
    #[error(
        "{solver} did not converge in {iterations} iterations: residual {residual:.3e} > tolerance {tolerance:.1e}"
    )]
    NoConvergence {
        /// The solver.
        solver: &'static str,
        /// Iterations done.
        iterations: usize,
        /// Relative residual reached.
        residual: f64,
        /// Requested tolerance.
        tolerance: f64,
    },
    /// A direct solver met a singular system.
    #[error("{what}: the linear system is singular or too ill-conditioned ({detail})")]
    Singular {
        /// Which system.
        what: &'static str,
        /// Solver detail.
        detail: String,
    },
    /// A parameter that fixes the structure was changed after compilation.
    #[error(
        "parameter `{name}` determines {what}, which is fixed when the model is compiled; compile again to change it"
    )]
    StructuralParameter {
        /// The parameter.
        name: String,
        /// What depends on it.
        what: String,
    },
    /// A request that makes no sense for this net or these options.
    #[error("{0}")]
    Invalid(String),
    /// The Farkas algorithm computing minimal invariants needed more
    /// intermediate rows than allowed (the number of minimal invariants, and of
    /// intermediate rows, can grow exponentially with the net).
    #[error(
        "computing the minimal {what} needs more than {limit} intermediate rows (limit reached after eliminating {eliminated} of {columns} columns); raise the limit (max_rows) if memory allows"
    )]
    InvariantRowLimit {
        /// "P-invariants" or "T-invariants".
        what: &'static str,
        /// The configured limit (`FarkasParams::max_rows`).
        limit: usize,
        /// Columns eliminated before the limit was reached.
        eliminated: usize,
        /// Columns that had to be eliminated (non-zero columns of the matrix).
        columns: usize,
    },
    /// A coefficient of an invariant (or of an intermediate row of the Farkas
    /// algorithm) does not fit the integers used: arc multiplicities that
    /// multiply along chains of places can make coefficients astronomically
    /// large.
    #[error(
        "computing the minimal {what}: a coefficient exceeds {limit} (after eliminating {eliminated} columns); the arc multiplicities make the invariants too large to represent"
    )]
    InvariantOverflow {
        /// "P-invariants" or "T-invariants".
        what: &'static str,
        /// The largest coefficient supported.
        limit: u128,
        /// Columns eliminated when it happened.
        eliminated: usize,
    },
    /// The rates of a solve are too far apart for double precision: scaled
    /// by the fastest, the slowest would fall below the range in which the
    /// elimination keeps its accuracy (see [`crate::ctmc::MAX_RATE_SPREAD`]).
    #[error(
        "the rates are too far apart for double precision: `{fastest}` = {max:e} is {ratio:.1e} times `{slowest}` = {min:e}, beyond the {limit:.0e} the solver can represent; rescale the time unit or leave the negligible transition out"
    )]
    RateSpread {
        /// The fastest timed transition.
        fastest: String,
        /// Its rate.
        max: f64,
        /// The slowest timed transition.
        slowest: String,
        /// Its rate.
        min: f64,
        /// `max / min` (may be infinite).
        ratio: f64,
        /// The largest ratio accepted.
        limit: f64,
    },
    /// A computed result (probability, throughput, measure, estimate,
    /// residual) is not a finite number: it is reported as an error rather
    /// than printed.
    #[error("{what} is not a finite number (got {value}): {cause}")]
    NotFinite {
        /// Which result, e.g. "the throughput of transition `t3`".
        what: String,
        /// The value computed (NaN or ±∞).
        value: f64,
        /// The likely cause, or what to change.
        cause: String,
    },
    /// A net file too large to read within the memory limit (checked
    /// before it is read: [`crate::io::read_file_within`]).
    #[error(
        "{} is {}: reading it would take about {} of memory, more than the limit of {} (by default 85 % of the memory available); raise it with --max-memory if the machine has more free memory",
        .path.display(), crate::error::format_bytes(*.bytes), crate::error::format_bytes(*.needed), crate::error::format_bytes(*.limit)
    )]
    FileTooLarge {
        /// The file.
        path: std::path::PathBuf,
        /// Its size.
        bytes: u64,
        /// The memory reading it would take.
        needed: u64,
        /// The limit.
        limit: u64,
    },
    /// A generator was asked for more than it makes (checked before
    /// anything is allocated).
    #[error("{what} would have {size} {unit}, more than the limit of {limit}")]
    SizeLimit {
        /// What is too large, e.g. "the net of philosophers 100000000".
        what: String,
        /// What is counted, e.g. "places and transitions".
        unit: &'static str,
        /// The size asked for.
        size: u64,
        /// The largest size accepted.
        limit: u64,
    },
    /// The structured engine does not apply to this net (no product
    /// structure, a component too large, a chain that is not irreducible):
    /// the explicit engine is the one to use.
    #[error("the structured engine does not apply: {reason}")]
    Unstructured {
        /// Why.
        reason: String,
    },
    /// A simulation ran out of its wall-clock budget
    /// (`SimParams::max_wall_s`).
    #[error(
        "the simulation used its {limit_s} s of wall-clock time after {events} firings, at simulated time {time:.6e} of run {run} (runs end at {end_time:.6e}; about {projected:.1e} firings would be needed); shorten the runs or raise the wall-time limit"
    )]
    WallTimeLimit {
        /// The budget, seconds.
        limit_s: f64,
        /// Firings done, all runs.
        events: u64,
        /// Simulated time within the current run.
        time: f64,
        /// The current run, from 1.
        run: usize,
        /// The end time of each run.
        end_time: f64,
        /// Firings all runs would need at the rate observed so far.
        projected: f64,
    },
    /// A simulation was stopped by its observer (for example on Ctrl-C).
    #[error(
        "the simulation was interrupted after {events} firings, at simulated time {time:.6e} of run {run} (runs end at {end_time:.6e})"
    )]
    Interrupted {
        /// Firings done, all runs.
        events: u64,
        /// Simulated time within the current run.
        time: f64,
        /// The current run, from 1.
        run: usize,
        /// The end time of each run.
        end_time: f64,
    },
    /// A computation was stopped by its caller through an
    /// [`Interrupt`](crate::Interrupt) (for example on Ctrl-C).
    #[error("stopped on request while {during}")]
    Cancelled {
        /// What was being done, e.g. "generating the reachability graph".
        during: &'static str,
    },
    /// A simulation reached its safety cap on transition firings
    /// (`SimParams::max_events`) before the end of its runs.
    #[error(
        "the simulation fired {limit} transitions, its limit, at simulated time {time:.6e} (runs end at {end_time:.6e}); raise max_events or shorten the runs"
    )]
    EventLimit {
        /// The cap on firings, over all runs.
        limit: u64,
        /// Simulated time (within the current run) when it was reached.
        time: f64,
        /// The end time of each run.
        end_time: f64,
    },
    /// A choice marking (docs/gspn.md, *Decisions*) was met by an analysis
    /// that needs every choice made: a steady-state solve or a simulation
    /// without a policy.
    #[error(
        "marking [{marking}] is a choice between {choices}: solve the net under a policy (--policy FILE, from `gspn optimize --policy-out`) or optimize it (`gspn optimize`)"
    )]
    Undecided {
        /// The marking, formatted.
        marking: String,
        /// Its actions.
        choices: String,
    },
    /// Decisions can be taken forever without time passing: an end
    /// component of choice markings (or of a Markov automaton's
    /// probabilistic states).
    #[error(
        "Zeno choice: {count} choice state(s) can be chosen in a cycle of immediate transitions forever, without time passing (e.g. {states}); give the cycle a timed transition or make one of its choices the only one"
    )]
    Zeno {
        /// How many states form the end component.
        count: usize,
        /// A few of them, printed.
        states: String,
    },
    /// A policy that does not fit the net it is applied to.
    #[error("policy {source_name}: {message}")]
    Policy {
        /// The policy file (or "the policy").
        source_name: String,
        /// What does not fit.
        message: String,
    },
    /// A property (`Pmax=? [F "goal"]`) that does not parse or does not fit
    /// the model.
    #[error("property `{text}`: {message}")]
    Property {
        /// The property as written.
        text: String,
        /// What is wrong.
        message: String,
    },
}

/// Shorthand for `Result<T, petri::Error>`.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `1.5 GiB`, `820 MiB`, `12 kiB`, `100 B`.
pub(crate) fn format_bytes(b: u64) -> String {
    const UNITS: [&str; 4] = ["B", "kiB", "MiB", "GiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}
