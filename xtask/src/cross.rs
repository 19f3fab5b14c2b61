//! `cargo xtask cross`: firmware-core built for the MCU target with the cross toolchain,
//! with no default features, each feature alone (`physics`, `defmt`: defmt is checked
//! here, on the target, as defmt's library guide says), and all of them.
use crate::toolchain::{cross_cmd, toolchain, TARGET};

/// The feature sets built.
#[derive(Clone, Copy)]
enum Features {
    /// `--no-default-features`.
    NoDefault,
    /// `physics` alone.
    Physics,
    /// `defmt` alone.
    Defmt,
    /// `--all-features`.
    All,
}

impl Features {
    const BUILDS: [Features; 4] = [
        Features::NoDefault,
        Features::Physics,
        Features::Defmt,
        Features::All,
    ];

    /// As the step names say it.
    fn name(self) -> &'static str {
        match self {
            Features::NoDefault => "no default features",
            Features::Physics => "physics",
            Features::Defmt => "defmt",
            Features::All => "all",
        }
    }

    /// cargo's arguments for it.
    fn args(self) -> &'static [&'static str] {
        match self {
            Features::NoDefault => &["--no-default-features"],
            Features::Physics => &["--no-default-features", "--features", "physics"],
            Features::Defmt => &["--no-default-features", "--features", "defmt"],
            Features::All => &["--all-features"],
        }
    }
}

/// `cargo xtask cross`.
pub fn cross(steps: &mut crate::Steps) {
    let name = |f: Features| format!("cross build firmware-core ({})", f.name());
    let Some(sysroot) = steps.prepare("cross toolchain", toolchain) else {
        for feats in Features::BUILDS {
            steps.skip(&name(feats), "no cross toolchain");
        }
        return;
    };
    for feats in Features::BUILDS {
        let mut c = cross_cmd(&sysroot, "cargo");
        c.current_dir(crate::root()).args([
            "build",
            "-p",
            "firmware-core",
            "--release",
            "--target",
            TARGET,
            "-Zbuild-std=core",
            "--target-dir",
        ]);
        c.arg(crate::root().join("target/thumb")).args(feats.args());
        steps.run(&name(feats), c);
    }
}
