//! One record of the store: what a run of `fit`, `verify`, `diagnose`, `batch` (one per
//! unit) or `demo` (one per model) made of one unit, with where it came from (the run
//! id, the tool's version and commit, the command and its options, the input's SHA-256).
use super::test_document::TestRecord;
pub use super::trace::Trace;
use crate::data::output_unit::OutputUnit;
use crate::diagnose::contract::Verdict as DiagnosisVerdict;
use crate::diagnose::EffectId;
use crate::error::{ErrorKind, HostError, Result};
use firmware_core::model::{COEFF_NAMES, N_COEFFS};
use serde::ser::SerializeStruct;
use serde::{Deserialize, Serialize, Serializer};
use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::Path;

/// The coefficients a record holds at T0.
pub const COEFFS: usize = N_COEFFS;

/// The id of one run: 16 random bytes, written as 32 lowercase hex digits (the blob's
/// `run_id` in format 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RunId(pub [u8; 16]);

impl RunId {
    /// A fresh id from the operating system's random source.
    pub fn fresh() -> Result<RunId> {
        let mut b = [0u8; 16];
        getrandom::fill(&mut b).map_err(|e| {
            HostError::new(
                ErrorKind::Internal,
                format!("no random source for a run id: {e}"),
            )
        })?;
        Ok(RunId(b))
    }

    /// From 32 hex digits (either case).
    pub fn parse(s: &str) -> Option<RunId> {
        if s.len() != 32 {
            return None;
        }
        let mut b = [0u8; 16];
        for (i, v) in b.iter_mut().enumerate() {
            *v = u8::from_str_radix(s.get(2 * i..2 * i + 2)?, 16).ok()?;
        }
        Some(RunId(b))
    }
}

impl std::fmt::Display for RunId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

/// The command that made a record (a closed set; the store's `command` column holds its
/// serde name).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "lowercase")]
#[strum(serialize_all = "lowercase")]
pub enum Command {
    /// `host-fit fit`.
    Fit,
    /// `host-fit verify`.
    Verify,
    /// `host-fit diagnose`.
    Diagnose,
    /// `host-fit batch`: one record per unit.
    Batch,
    /// `host-fit demo`: one record per model of the demo.
    Demo,
}

impl Command {
    /// Every command, in the order of the schema's check.
    pub const ALL: [Command; 5] = [
        Command::Fit,
        Command::Verify,
        Command::Diagnose,
        Command::Batch,
        Command::Demo,
    ];

    /// Its name on the command line and in the store (its serde name).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The command of a name in the store.
    pub fn from_name(s: &str) -> Option<Command> {
        s.parse().ok()
    }
}

/// How a unit of the batch ended, and the store's acceptance verdict (its serde name is
/// the one spelling: summary, JSON and store).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    strum::Display,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum UnitStatus {
    /// Fitted, and its blob passed acceptance.
    Pass,
    /// Fitted, and its blob failed acceptance.
    Fail,
    /// Fitted, but a band of the specification had no verification dwell to judge.
    NotJudged,
    /// Could not be processed (the reason says why).
    Error,
}

impl UnitStatus {
    /// `pass`, `fail`, `not_judged` or `error`, as the summary writes it (its serde
    /// name).
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl From<crate::acceptance::Verdict> for UnitStatus {
    fn from(v: crate::acceptance::Verdict) -> Self {
        use crate::acceptance::Verdict;
        match v {
            Verdict::Pass => UnitStatus::Pass,
            Verdict::Fail => UnitStatus::Fail,
            Verdict::NotJudged => UnitStatus::NotJudged,
        }
    }
}

/// How the tool was run: the command and every option with its value (the defaults
/// included), as the command line's parser saw them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Invocation {
    /// The subcommand's name.
    pub command: String,
    /// `{"option": "value" | ["v1", "v2"]}`.
    pub options: serde_json::Map<String, serde_json::Value>,
    /// When the run started (a store time): every record of the run carries it.
    pub started: Option<String>,
}

/// The version of host-fit and the commit it was built from (`unknown` when it was
/// built outside a git checkout).
pub fn tool_version() -> (&'static str, &'static str) {
    (env!("CARGO_PKG_VERSION"), env!("HOST_FIT_COMMIT"))
}

/// A reader that hashes what passes through it (the input is read once, for the
/// recording and for its SHA-256).
pub struct HashingReader<R> {
    inner: R,
    hasher: Sha256,
}

impl<R: Read> HashingReader<R> {
    /// Hash what `inner` gives.
    pub fn new(inner: R) -> Self {
        HashingReader {
            inner,
            hasher: Sha256::new(),
        }
    }

    /// Read to the end (what the reader above did not take) and return the SHA-256 of
    /// everything, as 64 lowercase hex digits.
    pub fn finish(mut self) -> std::io::Result<String> {
        std::io::copy(&mut self, &mut std::io::sink())?;
        Ok(hex(&self.hasher.finalize()))
    }
}

impl<R: Read> Read for HashingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// The SHA-256 of a file, as 64 lowercase hex digits; the error names the file.
pub fn sha256_file(path: &Path) -> Result<String> {
    let f = std::fs::File::open(path).map_err(|e| HostError::io(path, &e))?;
    HashingReader::new(std::io::BufReader::new(f))
        .finish()
        .map_err(|e| HostError::io(path, &e))
}

/// The CRC of an encoded blob: its last four bytes (little-endian), as the firmware
/// checks it.
pub fn blob_crc(blob: &[u8]) -> Option<u32> {
    let n = blob.len();
    (n >= 4).then(|| u32::from_le_bytes([blob[n - 4], blob[n - 3], blob[n - 2], blob[n - 1]]))
}

/// `blob` (encoded) with its `run_id` set to `run` (decoded, stamped, encoded again: its
/// CRC follows), so that a unit in the field leads back to its record.
pub fn stamp(blob: &[u8], run: RunId) -> Result<Vec<u8>> {
    use firmware_core::blob::{Blob, MAX_BLOB_LEN};
    let err = |e: firmware_core::error::Error| {
        HostError::new(
            ErrorKind::Internal,
            format!("cannot stamp the blob with its run id: {e}"),
        )
    };
    let mut b = Blob::decode(blob).map_err(err)?;
    b.run_id = firmware_core::blob::RunId(run.0);
    let mut buf = [0u8; MAX_BLOB_LEN];
    let n = b.encode(&mut buf).map_err(err)?;
    Ok(buf[..n].to_vec())
}

/// The run id a blob carries (format 4 on; None for none or an older blob).
pub fn blob_run_id(blob: &[u8]) -> Option<RunId> {
    let id = firmware_core::blob::BlobView::new(blob).ok()?.run_id();
    (!id.is_none()).then_some(RunId(id.0))
}

/// The 12 coefficients at T0 (in the recording's output unit per g and in it), with
/// their 1-sigma where the run knows them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtT0 {
    /// Reference temperature, C.
    pub t0_c: f64,
    /// kxx .. u0z ([`COEFF_NAMES`] order).
    pub values: [f64; 12],
    /// Their 1-sigma (None: the run does not estimate them, e.g. `verify` reads a blob).
    pub sigma: Option<[f64; 12]>,
}

impl Serialize for RunId {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl Serialize for AtT0 {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let named = |v: &[f64; COEFFS]| -> serde_json::Map<String, serde_json::Value> {
            COEFF_NAMES
                .iter()
                .zip(v)
                .map(|(n, x)| (n.to_string(), serde_json::json!(x)))
                .collect()
        };
        let mut st = s.serialize_struct("AtT0", 3)?;
        st.serialize_field("t0_c", &self.t0_c)?;
        st.serialize_field("values", &named(&self.values))?;
        st.serialize_field("sigma", &self.sigma.as_ref().map(named))?;
        st.end()
    }
}

/// The verdict against the acceptance specification (the store's `acceptance` column).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Judged {
    /// `pass`, `fail`, `not_judged` (the acceptance's own verdict) or `error` (a batch
    /// unit that could not be processed). The store's `acceptance` column holds `pass`,
    /// `fail` or `error`, and NULL for `not_judged` (with its reason), as for a run that
    /// judged nothing.
    pub verdict: UnitStatus,
    /// Why, in one sentence (the acceptance's reason, or the error).
    pub reason: String,
}

/// One record, as written and as read back.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// Its order in the store (0 before it is written).
    pub id: i64,
    /// The run id (in the blob, format 4 on).
    pub run_id: RunId,
    /// The unit's serial.
    pub serial: String,
    /// When its run started (UTC, RFC 3339): the units of a batch share their batch's.
    pub time_utc: String,
    /// host-fit's version.
    pub version: String,
    /// The commit host-fit was built from.
    pub commit: String,
    /// The command.
    pub command: Command,
    /// Its options (JSON object).
    pub options: serde_json::Value,
    /// The lot (batch: the folder's name or `--lot`; elsewhere `--lot`).
    pub lot: Option<String>,
    /// The input recording, as given.
    pub input: String,
    /// Its SHA-256 (None: a batch unit whose file could not be read).
    pub input_sha256: Option<String>,
    /// The recording's output unit (`V`, `mV`, ...).
    pub output_unit: Option<OutputUnit>,
    /// The model in the blob.
    pub model: Option<String>,
    /// The coefficients at T0.
    pub at_t0: Option<AtT0>,
    /// The blob made (fit, diagnose --out, batch, demo) or verified (verify).
    #[serde(skip)]
    pub blob: Option<Vec<u8>>,
    /// The acceptance.
    pub judged: Option<Judged>,
    /// The worst |dg| over the verification dwells, compensated, mg.
    pub worst_dg_mg: Option<f64>,
    /// The diagnosis' verdict.
    pub diagnosis_verdict: Option<DiagnosisVerdict>,
    /// The diagnosis' findings (the contract's `findings`, JSON).
    pub findings: Option<serde_json::Value>,
    /// Where and by whom.
    #[serde(flatten)]
    pub trace: Trace,
    /// The unit's test record for the line's systems (see [`super::test_record`]).
    #[serde(skip)]
    pub test_record: Option<TestRecord>,
}

impl Record {
    /// A record of `command` on the unit `serial` from `input`, stamped with a fresh run
    /// id, the time the run started (now, without an invocation) and the tool's version;
    /// the rest is filled by the command.
    pub fn new(
        command: Command,
        inv: Option<&Invocation>,
        serial: &str,
        input: &Path,
    ) -> Result<Record> {
        let (version, commit) = tool_version();
        Ok(Record {
            id: 0,
            run_id: RunId::fresh()?,
            serial: serial.to_string(),
            time_utc: inv
                .and_then(|i| i.started.clone())
                .unwrap_or_else(super::clock::now),
            version: version.into(),
            commit: commit.into(),
            command,
            options: serde_json::Value::Object(inv.map(|i| i.options.clone()).unwrap_or_default()),
            lot: None,
            input: input.display().to_string(),
            input_sha256: None,
            output_unit: None,
            model: None,
            at_t0: None,
            blob: None,
            judged: None,
            worst_dg_mg: None,
            diagnosis_verdict: None,
            findings: None,
            trace: Trace::default(),
            test_record: None,
        })
    }

    /// Fill the diagnosis columns from a diagnosis' JSON contract.
    pub fn with_diagnosis(&mut self, contract: &crate::diagnose::contract::Contract) -> Result<()> {
        let v = serde_json::to_value(contract).map_err(|e| {
            HostError::new(
                ErrorKind::Internal,
                format!("cannot encode the diagnosis: {e}"),
            )
        })?;
        self.diagnosis_verdict = Some(contract.verdict);
        self.findings = Some(v["findings"].clone());
        Ok(())
    }

    /// The catalogue ids of the stored findings, read by serde (only the ids: a record of
    /// an older contract reads while its effect names are this build's; a name this
    /// build does not know is an error, and a batch run again recomputes that unit).
    pub fn finding_effects(&self) -> Result<Vec<EffectId>> {
        /// The one field read of a stored finding.
        #[derive(serde::Deserialize)]
        struct Named {
            effect: EffectId,
        }
        match &self.findings {
            None => Ok(Vec::new()),
            Some(v) => Vec::<Named>::deserialize(v)
                .map(|n| n.into_iter().map(|n| n.effect).collect())
                .map_err(|e| {
                    HostError::new(
                        ErrorKind::Store,
                        format!(
                            "run {}: its stored findings are not the diagnosis contract's: {e}",
                            self.run_id
                        ),
                    )
                }),
        }
    }

    /// Fill the acceptance from a verdict and its reason.
    pub fn with_verdict(&mut self, verdict: impl Into<UnitStatus>, reason: &str) {
        self.judged = Some(Judged {
            verdict: verdict.into(),
            reason: reason.to_string(),
        });
    }

    /// Whether it is a calibration (see [`super::schema::CALIBRATION`]): it made a blob
    /// and did not end in an error.
    pub fn is_calibration(&self) -> bool {
        self.command != Command::Verify
            && self.blob.is_some()
            && self
                .judged
                .as_ref()
                .is_none_or(|j| j.verdict != UnitStatus::Error)
    }

    /// The blob's CRC (its last four bytes).
    pub fn blob_crc(&self) -> Option<u32> {
        self.blob.as_deref().and_then(blob_crc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_ids_are_fresh_and_read_back() {
        let a = RunId::fresh().unwrap();
        let b = RunId::fresh().unwrap();
        assert_ne!(a, b);
        let s = a.to_string();
        assert_eq!(s.len(), 32);
        assert!(s
            .bytes()
            .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase()));
        assert_eq!(RunId::parse(&s), Some(a));
        assert_eq!(RunId::parse(&s.to_uppercase()), Some(a));
        assert_eq!(RunId::parse(&s[1..]), None);
        assert_eq!(RunId::parse(&"g".repeat(32)), None);
    }

    #[test]
    fn sha256_of_a_known_text_and_while_reading() {
        // FIPS 180-2's example "abc"
        let abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        let mut r = HashingReader::new(&b"abc"[..]);
        let mut first = [0u8; 1];
        r.read_exact(&mut first).unwrap();
        // the rest is hashed by finish, though the reader above stopped early
        assert_eq!(r.finish().unwrap(), abc);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x");
        std::fs::write(&p, "abc").unwrap();
        assert_eq!(sha256_file(&p).unwrap(), abc);
        let e = sha256_file(&dir.path().join("missing")).unwrap_err();
        assert!(e.to_string().contains("missing"), "{e}");
    }

    #[test]
    fn closed_sets_are_named_once_and_read_back() {
        for c in Command::ALL {
            assert_eq!(Command::from_name(c.name()), Some(c));
        }
        assert_eq!(Command::Batch.name(), "batch");
        for v in [
            UnitStatus::Pass,
            UnitStatus::Fail,
            UnitStatus::NotJudged,
            UnitStatus::Error,
        ] {
            assert_eq!(v.name().parse::<UnitStatus>().ok(), Some(v));
        }
        assert_eq!(UnitStatus::NotJudged.name(), "not_judged");
        assert_eq!(Command::from_name("refit"), None);
        let mut r = Record::new(Command::Verify, None, "SN", Path::new("r.csv")).unwrap();
        r.with_verdict(crate::acceptance::Verdict::Fail, "over");
        assert_eq!(r.judged.as_ref().unwrap().verdict, UnitStatus::Fail);
        assert_eq!(blob_crc(&[1, 2, 0x78, 0x56, 0x34, 0x12]), Some(0x1234_5678));
    }
}
