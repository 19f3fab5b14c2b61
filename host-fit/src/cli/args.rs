//! The command line's grammar: every command and option, with its help text. Its enums
//! are the command line's own (clap's `ValueEnum`); each maps onto the library's.
use crate::blind::Class;
use crate::fit::pipeline::ModelKind;
use crate::fit::route::Route;
use crate::store::record::Trace;
use clap::{Args, Parser, Subcommand, ValueEnum};
use firmware_core::compensate::ErrorModel;
use std::path::PathBuf;

/// Calibration and temperature compensation of a triaxial accelerometer: the bench tool.
#[derive(Parser, Debug)]
#[command(name = "host-fit", version, about)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// Method-2 error model.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrModel {
    /// Formulas (6)/(7).
    Full,
    /// Formula (8).
    Simplified,
}

impl From<ErrModel> for ErrorModel {
    fn from(e: ErrModel) -> Self {
        match e {
            ErrModel::Full => ErrorModel::Full,
            ErrModel::Simplified => ErrorModel::Simplified,
        }
    }
}

/// The compensation method of `verify`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// Correct the constants.
    #[value(name = "1")]
    One,
    /// Correct the result.
    #[value(name = "2")]
    Two,
}

impl MethodArg {
    /// `1` or `2`, as the outputs name it: its name on the command line.
    pub fn name(self) -> String {
        self.to_possible_value()
            .map(|v| v.get_name().to_string())
            .unwrap_or_default()
    }
}

/// A temperature model family.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelArg {
    /// Piecewise-linear through breakpoints.
    Pwl,
    /// Polynomial of dT.
    Poly,
}

impl From<ModelArg> for ModelKind {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Pwl => ModelKind::Pwl,
            ModelArg::Poly => ModelKind::Poly,
        }
    }
}

/// An identification route.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RouteArg {
    /// Chosen by the data: the static route, or the dynamic one for a sweep and for a
    /// stop-and-soak test whose dwells still settle (when the held-out blocks keep a lag).
    Auto,
    /// The dwells in thermal equilibrium.
    Static,
    /// Every dwell, ramps included.
    Joint,
    /// The paper's: formula (10) per stop, then a fit across stops.
    PerStop,
    /// Every window through temperature changes, jointly with the unit's thermal lag and
    /// rate where held-out blocks of time support them (chosen by itself for a sweep).
    Dynamic,
}

impl From<RouteArg> for Option<Route> {
    /// The route asked for; None: chosen by the data.
    fn from(r: RouteArg) -> Self {
        match r {
            RouteArg::Auto => None,
            RouteArg::Static => Some(Route::Static),
            RouteArg::Joint => Some(Route::Joint),
            RouteArg::PerStop => Some(Route::PerStop),
            RouteArg::Dynamic => Some(Route::Dynamic),
        }
    }
}

/// The temperature model options.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// Temperature model family (default for a recording: chosen by the data, by
    /// cross-validation over the calibration dwells, which also choose the order or
    /// breakpoints within a family given alone; for a table: pwl).
    #[arg(long, value_enum)]
    pub model: Option<ModelArg>,
    /// Polynomial order (poly only; default: chosen by the data).
    #[arg(long)]
    pub order: Option<usize>,
    /// Breakpoints for pwl, C, comma-separated (pwl only; default: the calibration
    /// temperatures).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub breakpoints: Option<Vec<f64>>,
}

/// The acceptance specification.
#[derive(Args, Debug, Clone)]
pub struct AcceptArgs {
    /// Limit on |dg| within +-5 C of T0, mg.
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    pub accept_t0_mg: f64,
    /// Limit on |dg| over the rest of the valid range, mg.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub accept_range_mg: f64,
    /// Verification dwells outside the blob's valid range: `fail` the unit (it was
    /// tested where its blob claims nothing), or `report` them apart (a band of the
    /// specification they leave without a judged dwell is then not judged).
    #[arg(long, value_enum, default_value_t = OutsideArg::Fail)]
    pub outside_range: OutsideArg,
}

impl AcceptArgs {
    /// The specification these options give, checked.
    pub fn spec(&self) -> crate::error::Result<crate::acceptance::Spec> {
        Ok(
            crate::acceptance::Spec::new(self.accept_t0_mg, self.accept_range_mg)?
                .with_outside_range(self.outside_range.into()),
        )
    }
}

/// What becomes of verification dwells outside the blob's valid range.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutsideArg {
    /// They fail the unit.
    Fail,
    /// They are reported apart.
    Report,
}

impl From<OutsideArg> for crate::acceptance::OutsideRange {
    fn from(o: OutsideArg) -> Self {
        match o {
            OutsideArg::Fail => crate::acceptance::OutsideRange::Fail,
            OutsideArg::Report => crate::acceptance::OutsideRange::Report,
        }
    }
}

/// The positions options, the same for every command that reads recordings.
#[derive(Args, Debug, Clone, Default)]
pub struct PositionArgs {
    /// Positions file (name,fx,fy,fz[,role]; an empty vector `W1,,,` is a pose of
    /// unknown orientation, estimated from the data).
    #[arg(long)]
    pub positions: Option<PathBuf>,
    /// Positions kept out of every fit and judged (default: those whose role is
    /// verification, PP1..PP6 unless a positions file says otherwise).
    #[arg(long, value_delimiter = ',')]
    pub positions_for_check: Option<Vec<String>>,
    /// Treat every vector of the positions file as unknown (vectors that were
    /// themselves estimated from data): estimate them.
    #[arg(long, requires = "positions")]
    pub unknown_orientations: bool,
}

/// A check at the door that data may be let past (`--allow`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AllowArg {
    /// Outputs whose change per g is implausible for their stated unit.
    OutputScale,
    /// Temperatures that look like Kelvin or Fahrenheit.
    TemperatureScale,
    /// A recording that covers less than its test promised (its T0 outside the data, a
    /// test cut off on its way to its next stop): fitted over the range it covers.
    Partial,
}

impl From<AllowArg> for crate::data::door::Check {
    fn from(a: AllowArg) -> Self {
        use crate::data::door::Check;
        match a {
            AllowArg::OutputScale => Check::OutputScale,
            AllowArg::TemperatureScale => Check::TemperatureScale,
            AllowArg::Partial => Check::Partial,
        }
    }
}

/// A recording and its positions.
#[derive(Args, Debug, Clone)]
pub struct Input {
    /// The recording.
    pub recording: PathBuf,
    /// Its positions.
    #[command(flatten)]
    pub positions: PositionArgs,
    /// Also print the notes on expected features of the data (dwells resting through
    /// temperature ramps), which are otherwise left out.
    #[arg(long)]
    pub verbose: bool,
    /// Let the data past these checks at the door (comma-separated), each then a
    /// warning: output-scale (outputs implausible for their unit), temperature-scale
    /// (temperatures that look like Kelvin or Fahrenheit), partial (a recording that
    /// covers less than its test promised; refused only where a blob is written).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub allow: Vec<AllowArg>,
}

/// Where a run is recorded (the record store; `history` and `trend` read it).
#[derive(Args, Debug, Clone, Default)]
pub struct RecordArgs {
    /// Record the run in this record store: a file path (SQLite, created when missing;
    /// `batch`: records.sqlite in its output folder unless given) or
    /// postgresql://user@host:port/database (the password from PGPASSWORD or a pgpass
    /// file; docs/records.md).
    #[arg(long)]
    pub db: Option<String>,
    /// The unit's lot, recorded with the run (`batch`: default the folder's name).
    #[arg(long)]
    pub lot: Option<String>,
    /// Where and by whom (`--station`, `--chamber`, `--tilter`, `--operator`, ...).
    #[command(flatten)]
    pub trace: TraceArgs,
    /// How the tool was run (filled by the command line; not an option).
    #[arg(skip)]
    pub invocation: Option<crate::store::Invocation>,
}

/// Where and by whom: one flag per field of [`Trace`] (`--NAME`, its environment variable
/// and help from [`Trace::FIELDS`]), so that a field added to the record's type is a flag
/// without a line here.
#[derive(Debug, Clone, Default)]
pub struct TraceArgs(pub Trace);

impl clap::FromArgMatches for TraceArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        Ok(TraceArgs(Trace::from_fields(|n| {
            m.try_get_one::<String>(n).ok().flatten().cloned()
        })))
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl Args for TraceArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        Trace::FIELDS.iter().fold(cmd, |c, f| {
            c.arg(clap::Arg::new(f.name).long(f.name).env(f.env).help(f.help))
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// `temp-fit`.
#[derive(Args, Debug)]
pub struct TempFitArgs {
    /// The table: temp_c,kxx,kyy,kzz,kxy,kxz,kyx,kyz,kzx,kzy,u0x,u0y,u0z.
    pub coeffs: PathBuf,
    /// The temperature model.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Reference temperature T0, C.
    #[arg(long, default_value_t = 20.0, allow_hyphen_values = true)]
    pub t0: f64,
    /// Report scale and cross terms as the paper's relative beta/gamma.
    #[arg(long)]
    pub relative: bool,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
}

/// `identify`.
#[derive(Args, Debug)]
pub struct IdentifyArgs {
    /// The recording and its positions.
    #[command(flatten)]
    pub input: Input,
    /// Write the per-stop table in the format of paper-tables.csv.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Overwrite an existing output.
    #[arg(long)]
    pub force: bool,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
}

/// `fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// The recording and its positions.
    #[command(flatten)]
    pub input: Input,
    /// The temperature model.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Identification route: auto (chosen by the data, below), static (the dwells in
    /// thermal equilibrium), joint (every dwell, ramps included), per-stop (the paper's),
    /// dynamic (every window, jointly with the thermal lag and rate the held-out blocks
    /// support). Auto: a recording whose dwells mostly move in temperature (a sweep)
    /// takes the dynamic route; a stop-and-soak test whose dwells still carry the
    /// element's settling (a lag explaining a share of the static fit's residual) is
    /// fitted on the dynamic route too and kept there when the held-out blocks keep the
    /// lag; otherwise the static route. `--model` keeps the static route.
    #[arg(long, value_enum, default_value = "auto")]
    pub route: RouteArg,
    /// The serial written into the blob (default: the recording's `unit`).
    #[arg(long)]
    pub serial: Option<String>,
    /// Recompute the firmware's cached matrices after this temperature change, C
    /// (default: chosen from the unit's own slopes so that the cache never costs more
    /// than a verification dwell's own noise anywhere in the valid range, at most 0.1;
    /// 0: the model at every temperature).
    #[arg(long)]
    pub update_step: Option<f64>,
    /// Clamp the temperature to the valid range instead of extrapolating.
    #[arg(long)]
    pub clamp: bool,
    /// The blob to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Overwrite an existing output.
    #[arg(long)]
    pub force: bool,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
    /// Where the run is recorded.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// `verify`.
#[derive(Args, Debug)]
pub struct VerifyArgs {
    /// The recording and its positions.
    #[command(flatten)]
    pub input: Input,
    /// The coefficient blob.
    #[arg(long)]
    pub blob: PathBuf,
    /// 1: correct the constants; 2: correct the result.
    #[arg(long, value_enum, default_value = "1")]
    pub method: MethodArg,
    /// Error model of method 2 (default: full); an error with method 1, which has none.
    #[arg(long, value_enum)]
    pub error_model: Option<ErrModel>,
    /// The acceptance specification.
    #[command(flatten)]
    pub accept: AcceptArgs,
    /// Verify even when the blob's serial is not the recording's unit.
    #[arg(long)]
    pub force: bool,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
    /// Where the run is recorded.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// `report`.
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The recording and its positions.
    #[command(flatten)]
    pub input: Input,
    /// The HTML file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// The twin's truth, for a simulated recording (`simulate --truth`, or a demo's
    /// truth.json): drawn in the coefficient plots, and the departures taken from it.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Overwrite an existing file.
    #[arg(long)]
    pub force: bool,
}

/// `diagnose`.
#[derive(Args, Debug)]
pub struct DiagnoseArgs {
    /// The recording and its positions.
    #[command(flatten)]
    pub input: Input,
    /// Write an HTML report with residual plots before and after.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the extended model (tables and in-flight physics terms) as a blob.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The serial written into the blob (default: the recording's `unit`).
    #[arg(long, requires = "out")]
    pub serial: Option<String>,
    /// Overwrite existing outputs.
    #[arg(long)]
    pub force: bool,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
    /// Where the run is recorded.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// `batch`.
#[derive(Args, Debug)]
pub struct BatchArgs {
    /// Folder of recordings (*.csv).
    pub dir: PathBuf,
    /// Output folder: one blob and one JSON per unit, and summary.csv.
    #[arg(long)]
    pub out: PathBuf,
    /// Parallel jobs (default: one per core).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Temperature model (default: chosen by the data for every unit).
    #[arg(long, value_enum)]
    pub model: Option<ModelArg>,
    /// The positions of every unit's recording.
    #[command(flatten)]
    pub positions: PositionArgs,
    /// The acceptance specification.
    #[command(flatten)]
    pub accept: AcceptArgs,
    /// Also run the diagnosis on every unit; the blob and the verification are then
    /// the diagnosed model's.
    #[arg(long)]
    pub diagnose: bool,
    /// Overwrite outputs of an earlier run.
    #[arg(long)]
    pub force: bool,
    /// Where the units are recorded.
    #[command(flatten)]
    pub record: RecordArgs,
    /// Record nothing (no record store).
    #[arg(long, conflicts_with = "db")]
    pub no_db: bool,
    /// Let every unit's data past these checks at the door (comma-separated; as `fit
    /// --allow`): output-scale, temperature-scale, partial.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub allow: Vec<AllowArg>,
}

/// `blind`.
#[derive(Args, Debug)]
pub struct BlindArgs {
    /// The long suite (more seeds, magnitudes down to the edge of detectability).
    #[arg(long)]
    pub long: bool,
    /// Run only the cases whose name contains this, and print each one's diagnosis.
    #[arg(long)]
    pub only: Option<String>,
    /// Run only the cases of these classes (comma-separated, e.g.
    /// `slow,digital,re-clamped,mixtures`).
    #[arg(long, value_delimiter = ',', value_parser = class_parser())]
    pub class: Vec<Class>,
}

/// `--class`: one of the blind suite's classes by its name ([`Class`]'s own names, listed
/// in `--help` and in the error for any other).
fn class_parser() -> impl clap::builder::TypedValueParser<Value = Class> {
    use clap::builder::{PossibleValuesParser, TypedValueParser};
    use strum::IntoEnumIterator;
    PossibleValuesParser::new(Class::iter().map(<&'static str>::from))
        .try_map(|s| s.parse::<Class>())
}

/// `simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// TOML configuration (default: the built-in paper unit and profile).
    pub config: Option<PathBuf>,
    /// The recording to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Random seed (overrides the configuration's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Also write the truth (all parameters) as JSON here.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// A chamber and tilter program to run instead of the configuration's stops (CSV
    /// `time_s,setpoint_c,position`, docs/chamber-program.md; `host-fit plan` writes
    /// one): a plan tried on the twin before a chamber is booked.
    #[arg(long)]
    pub plan: Option<PathBuf>,
    /// Where to write the positions file the recording needs (a `[flight]`
    /// configuration's attitudes; required with one).
    #[arg(long)]
    pub positions_out: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long)]
    pub force: bool,
}

/// `plan`.
#[derive(Args, Debug)]
pub struct PlanArgs {
    /// The chamber's range, C: `LO,HI`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, default_values_t = [-40.0, 70.0])]
    pub range_c: Vec<f64>,
    /// The chamber's fastest ramp, C/min.
    #[arg(long, default_value_t = crate::plan::DEFAULT_MAX_RAMP_C_PER_MIN)]
    pub max_ramp_c_per_min: f64,
    /// The tilter's positions, in the order visited.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "TP1,TP2,TP3,TP4,TP5,TP6,PP1,PP2,PP3,PP4,PP5,PP6"
    )]
    pub positions: Vec<String>,
    /// Dwell per position, s.
    #[arg(long, default_value_t = 50.0)]
    pub dwell_s: f64,
    /// Move between positions, s.
    #[arg(long, default_value_t = 10.0)]
    pub move_s: f64,
    /// Samples per second.
    #[arg(long, default_value_t = 1.0)]
    pub rate_hz: f64,
    /// The unit type's output noise, 1 sigma per sample (output units; default 2e-5, or
    /// the diagnosis's with --from-diagnosis).
    #[arg(long)]
    pub noise: Option<f64>,
    /// The unit type's thermal time constant (its element behind its sensor), s (default
    /// 0, or the diagnosis's with --from-diagnosis).
    #[arg(long)]
    pub tau_s: Option<f64>,
    /// An earlier `diagnose --json` of a unit of the type: its thermal_lag finding's
    /// time constant (the slowest axis) and its noise per sample (the noisiest axis) are
    /// used where --tau-s and --noise are not given; a hysteresis found beside a rate or a
    /// lag ends every stop-and-soak program with a return that separates them, and no
    /// sweep is chosen (docs/chamber-program.md).
    #[arg(long)]
    pub from_diagnosis: Option<PathBuf>,
    /// Also write an HTML page plotting every candidate's predicted accuracy against
    /// its chamber hours, the chosen one ringed.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Target: the shortest plan predicted within this worst verification |dg|, mg.
    #[arg(long, conflicts_with = "hours")]
    pub target_mg: Option<f64>,
    /// Target: the most accurate plan within this many chamber hours.
    #[arg(long)]
    pub hours: Option<f64>,
    /// Seed of the twin the candidates are tried on.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The program to write (CSV time_s,setpoint_c,position; docs/chamber-program.md).
    #[arg(long)]
    pub out: PathBuf,
    /// Overwrite an existing program.
    #[arg(long)]
    pub force: bool,
    /// JSON output.
    #[arg(long)]
    pub json: bool,
}

/// `demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "demo-out")]
    pub out: PathBuf,
    /// Random seed of the simulation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Overwrite the outputs of an earlier run.
    #[arg(long)]
    pub force: bool,
}

/// `fw-vectors`.
#[derive(Args, Debug)]
pub struct FwVectorsArgs {
    /// The blob.
    #[arg(long)]
    pub blob: PathBuf,
    /// Write a new input table here (else read --inputs).
    #[arg(long)]
    pub make_inputs: Option<PathBuf>,
    /// The input table to evaluate.
    #[arg(long)]
    pub inputs: Option<PathBuf>,
    /// Random samples in a new table (edge cases are appended).
    #[arg(long, default_value_t = 64)]
    pub n: usize,
    /// Seed of a new table.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Prefix of the method tags in the output (the harness prints `p` for the
    /// blob with physics terms).
    #[arg(long, default_value = "")]
    pub tag_prefix: String,
    /// Overwrite an existing table.
    #[arg(long)]
    pub force: bool,
}

/// `inspect`.
#[derive(Args, Debug)]
pub struct InspectArgs {
    /// The blob.
    pub blob: PathBuf,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
}

/// `history`.
#[derive(Args, Debug)]
pub struct HistoryArgs {
    /// The unit's serial (as in its blob).
    pub serial: String,
    /// The record store (a file, or postgresql://user@host:port/database).
    #[arg(long)]
    pub db: String,
    /// Print the unit's test record (JSON) of its newest record that has one, or of the
    /// run given with --run.
    #[arg(long, conflicts_with_all = ["blob", "json"])]
    pub test_record: bool,
    /// With --test-record: the run (its id or its first 6 or more hex digits).
    #[arg(long, requires = "test_record")]
    pub run: Option<String>,
    /// Re-issue the blob of this run, bit for bit (its run id, or its first 6 or more
    /// hex digits); needs --out.
    #[arg(long, requires = "out")]
    pub blob: Option<String>,
    /// Where to write the re-issued blob.
    #[arg(long, requires = "blob")]
    pub out: Option<PathBuf>,
    /// Overwrite an existing --out.
    #[arg(long)]
    pub force: bool,
    /// Machine-readable output.
    #[arg(long)]
    pub json: bool,
}

/// `trend`.
#[derive(Args, Debug)]
pub struct TrendArgs {
    /// The record store (a file, or postgresql://user@host:port/database).
    #[arg(long)]
    pub db: String,
    /// The HTML report to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Centre lines and limits from the first N units in time order (default 50).
    #[arg(long, conflicts_with_all = ["reference_from", "reference_to"])]
    pub reference_first: Option<usize>,
    /// ... or from the units calibrated from this date or UTC time (YYYY-MM-DD or
    /// YYYY-MM-DDTHH:MM:SSZ) ...
    #[arg(long, requires = "reference_to")]
    pub reference_from: Option<String>,
    /// ... to this one (a date alone: to its end).
    #[arg(long, requires = "reference_from")]
    pub reference_to: Option<String>,
    /// The run rules that flag points: Nelson's numbers, comma-separated, or `all`.
    #[arg(long, default_value = "all")]
    pub rules: String,
    /// Overwrite an existing report.
    #[arg(long)]
    pub force: bool,
    /// Machine-readable output (every flagged point).
    #[arg(long)]
    pub json: bool,
}

/// `store`.
#[derive(Args, Debug)]
pub struct StoreArgs {
    /// What to do.
    #[command(subcommand)]
    pub action: StoreAction,
}

/// What `store` does.
#[derive(Subcommand, Debug)]
pub enum StoreAction {
    /// Bring a record store to this host-fit's schema version (a new one is made; an
    /// older one is upgraded in one transaction: back it up first).
    Migrate {
        /// The record store (a file, or postgresql://user@host:port/database).
        #[arg(long)]
        db: String,
    },
    /// Copy every record of one store into another, between backends too (records
    /// the destination holds already are not copied again).
    Copy {
        /// The store to copy from.
        src: String,
        /// The store to copy into (made when missing or empty).
        dst: String,
    },
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Fit temperature models to a coefficient table (format of paper-tables.csv).
    TempFit(TempFitArgs),
    /// Identify the 12 coefficients at every calibration stop (the paper's formula (10)).
    Identify(IdentifyArgs),
    /// Fit a recording and write the coefficient blob.
    Fit(FitArgs),
    /// Formula (13) in the verification dwells, uncompensated and compensated.
    Verify(VerifyArgs),
    /// The engineer's HTML report of a recording: the paper's and richer models,
    /// compensated through firmware-core, dg per verification position, the coefficients
    /// against temperature, residuals against time.
    Report(ReportArgs),
    /// Locate where the model and a recording disagree, name the physics left out,
    /// model it and show the fit improve (JSON contract at-diagnosis/1).
    Diagnose(DiagnoseArgs),
    /// Fit (and optionally diagnose) every recording in a folder, in parallel.
    Batch(BatchArgs),
    /// Blind tests of the diagnosis on simulated recordings with concealed effects.
    Blind(BlindArgs),
    /// Simulate a unit's production temperature test (the digital twin).
    Simulate(SimulateArgs),
    /// Design a chamber and tilter program for a target accuracy or a number of hours:
    /// candidate plans tried on the twin, their predicted accuracy against chamber
    /// hours, the chosen program written with an equilibrium verification block.
    Plan(PlanArgs),
    /// The main job: simulate the paper's experiment, fit, compensate, summarise, report.
    Demo(DemoArgs),
    /// Firmware test vectors: write an input table, or print the expected f32 results
    /// (as bits) of the firmware-core code on it (used by `cargo xtask embedded`).
    FwVectors(FwVectorsArgs),
    /// Decode a blob and print it, or say why it is invalid.
    Inspect(InspectArgs),
    /// Every record of a unit in a record store, its latest calibration marked; a stored
    /// blob re-issued bit for bit.
    History(HistoryArgs),
    /// Control charts across lots from a record store: each coefficient at T0 and the
    /// worst verification |dg|, with limits from a reference period and the points the
    /// run rules flag (HTML report).
    Trend(TrendArgs),
    /// The record store itself: upgrade its schema (`migrate`), copy it between
    /// backends (`copy`).
    Store(StoreArgs),
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// clap's own consistency check of the whole grammar: a traceability field named as
    /// another option of a command (`--out`, `--db`) would fail it.
    #[test]
    fn the_grammar_is_consistent() {
        Cli::command().debug_assert();
    }

    /// Every field of the trace is a flag of a recording command, read into its field.
    #[test]
    fn every_trace_field_is_a_flag() {
        let mut args = vec!["host-fit".to_string(), "fit".into(), "r.csv".into()];
        args.extend(["--out".to_string(), "r.blob".into()]);
        for f in Trace::FIELDS {
            args.push(format!("--{}", f.name));
            args.push(format!("{}-flag", f.name));
        }
        let cli = Cli::try_parse_from(&args).unwrap();
        let Command::Fit(a) = cli.command else {
            panic!("not fit")
        };
        for (n, v) in a.record.trace.0.fields() {
            assert_eq!(v, Some(format!("{n}-flag")));
        }
    }
}
