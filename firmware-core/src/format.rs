//! The blob format's version: a leaf module, so the blob (which writes it) and the error
//! type (which names it in a refusal) both import it without importing each other.

/// The blob format version this firmware reads and writes (4: every time constant in
/// seconds, the output unit and the run id; see [`crate::blob`]).
pub const FORMAT_VERSION: u16 = 4;
