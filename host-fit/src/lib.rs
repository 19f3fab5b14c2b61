//! The bench side of the accelerometer calibration: read recordings, identify the 12
//! coefficients, fit their temperature models, build coefficient blobs, verify, simulate
//! the production test, diagnose what the model leaves out, report.
//!
//! The model itself (formulas (1)-(8), (13)) is `firmware-core`'s, evaluated here in
//! f64 and, for checks, in the firmware's own f32 path.
//!
//! The modules are layered; each uses only modules of its own layer or below (the tidy
//! test `tests/tidy.rs` holds it, and that no module imports in a circle):
//!
//! | layer | modules | what |
//! |---|---|---|
//! | 0 | `error`, `rng`, `output`, `progress` | foundations: errors, random numbers, atomic writes, JSON/CSV, progress of long work |
//! | 1 | `data`, `terms` | recordings, positions with their roles, stops and windows, coefficient tables; the vocabulary of discovered terms (parse, print, evaluate, a blob's term table) |
//! | 2 | `model` | the engine: one least-squares solver, the temperature basis, the floor, the windows and their weights, the terms and their columns, the solve with held-out blocks, the judge, the flashed model, its cache and f32 check |
//! | 3 | `fit`, `fuzzing`, `simulate` | identification, temperature models, the pipeline, the route (detection, the dynamic fit, the choice, the calibration), the predicted error; what the fuzz targets of the readers hold (replayed by the tests); the digital twin |
//! | 4 | `blob`, `verify`, `vectors`, `acceptance` | blobs built and read, formula (13) through firmware-core, firmware test vectors, pass/fail against a specification |
//! | 5 | `diagnose` | the search for what the paper's model leaves out, the findings, where the rest is, the JSON contract |
//! | 6 | `analysis`, `blind`, `plan`, `store` | the demo's comparison (pure), the blind tests of the diagnosis, chamber programs designed for a target accuracy, the record store (SQLite: records, history, trends) |
//! | 7 | `report`, `batch`, `demo`, `demo_plan` | HTML reports, production batches, the main job's files (and its plan beside the paper's test) |
//! | 8 | `cli` | the command line |
#![forbid(unsafe_code)]

pub mod error;
pub mod output;
pub mod progress;
pub mod rng;

pub mod data;
pub mod terms;

pub mod model;

pub mod fit;
pub mod fuzzing;
pub mod simulate;

pub mod acceptance;
pub mod blob;
pub mod vectors;
pub mod verify;

pub mod diagnose;

pub mod analysis;
pub mod blind;
pub mod plan;
pub mod store;

pub mod batch;
pub mod demo;
pub mod demo_plan;
pub mod report;

pub mod cli;
