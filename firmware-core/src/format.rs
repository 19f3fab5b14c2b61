//! The blob format's versions: a leaf module, so the blob (which writes them) and the
//! error type (which names them in a refusal) both import it without importing each other.

/// The newest blob format version this firmware reads and writes (5: format 4 and the
/// table of discovered terms; see [`crate::blob`]).
pub const FORMAT_VERSION: u16 = 5;

/// The oldest version this firmware reads (4: every time constant in seconds, the output
/// unit and the run id). A blob without discovered terms is written as version 4, byte
/// for byte as format 4 wrote it, so firmware of format 4 keeps reading it.
pub const OLDEST_FORMAT_VERSION: u16 = 4;
