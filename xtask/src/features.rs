//! The flash cost of each opt-in feature (Cortex-M4F): `examples/feature_cost.rs` built once per probe, the cost
//! of a feature being the flash of its probe image minus the flash of its baseline image.
//!
//! Every image is built in release (LTO) into the one target dir, with `--no-default-features --features
//! storage,accelerometer,mpu6050` (the unused features are in every image alike), except the calibration path's
//! second image, which adds the default features.

use std::path::PathBuf;
use std::process::Command;

use serde::Serialize;

use crate::elf::ImageSizes;
use crate::firmware::{PROFILE, example_executable, workspace_root};

/// The target the feature costs are measured on.
pub const TRIPLE: &str = "thumbv7em-none-eabihf";

/// The opt-in features every probe image is built with.
const PROBE_FEATURES: &str = "storage,accelerometer,mpu6050";

/// One image: a probe of `examples/feature_cost.rs`, with or without the default features.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Image {
    /// `ACCELCAL_FEATURE_COST_PROBE`.
    pub probe: &'static str,
    /// The default features (mpu6050, micromath, default-rng) on.
    pub default_features: bool,
}

const fn image(probe: &'static str, default_features: bool) -> Image {
    Image { probe, default_features }
}

/// One row of the table: what is measured, its image and its baseline.
pub struct Row {
    /// What the cost is of.
    pub what: &'static str,
    /// The image with it.
    pub with: Image,
    /// The image without it.
    pub without: Image,
}

/// The rows of the table, in order.
pub const ROWS: [Row; 6] = [
    Row { what: "blob v2 encode + decode", with: image("blob", false), without: image("none", false) },
    Row {
        what: "storage new + store + load (with the blob)",
        with: image("storage", false),
        without: image("none", false),
    },
    Row { what: "storage beyond the blob", with: image("storage", false), without: image("blob", false) },
    Row {
        what: "accelerometer adapter (one read)",
        with: image("accelerometer", false),
        without: image("none", false),
    },
    Row { what: "MPU-6050 driver (init + one read)", with: image("mpu6050", false), without: image("none", false) },
    Row {
        what: "default features on the calibration path",
        with: image("calibrate", true),
        without: image("calibrate", false),
    },
];

/// One measured cost.
#[derive(Debug, Clone, Serialize)]
pub struct FeatureCost {
    /// What the cost is of.
    pub what: &'static str,
    /// The probe image: `probe` or `probe+default`.
    pub image: String,
    /// The baseline image.
    pub baseline: String,
    /// Flash bytes of the probe image.
    pub image_flash: u64,
    /// Flash bytes of the baseline image.
    pub baseline_flash: u64,
    /// `image_flash - baseline_flash`.
    pub cost_bytes: i64,
}

impl Image {
    fn label(self) -> String {
        if self.default_features { format!("{}+default", self.probe) } else { self.probe.to_string() }
    }
}

/// The images `ROWS` need, each once, in build order (the images without the default features first).
pub fn images() -> Vec<Image> {
    let mut all: Vec<Image> = ROWS.iter().flat_map(|r| [r.with, r.without]).collect();
    all.sort_by_key(|i| (i.default_features, i.probe));
    all.dedup();
    all
}

/// Builds one probe image; its ELF file (overwritten by the next probe's build: read it first).
fn build(image: Image) -> Result<PathBuf, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(workspace_root()).env("ACCELCAL_FEATURE_COST_PROBE", image.probe);
    cmd.args(["build", "-p", "accelcal", "--quiet", "--message-format=json", "--profile", PROFILE]);
    cmd.args(["--target", TRIPLE, "--example", "feature_cost", "--features", PROBE_FEATURES]);
    if !image.default_features {
        cmd.arg("--no-default-features");
    }
    let out = cmd.output().map_err(|e| format!("feature_cost build: cannot run cargo: {e}"))?;
    if !out.status.success() {
        return Err(format!("feature_cost {} build failed:\n{}", image.label(), String::from_utf8_lossy(&out.stderr)));
    }
    example_executable(&out.stdout, "feature_cost").ok_or_else(|| "cargo build did not report feature_cost".into())
}

/// Builds every image of [`ROWS`] in turn and gives the cost of each row.
pub fn measure() -> Result<Vec<FeatureCost>, String> {
    let mut flash = std::collections::BTreeMap::new();
    for image in images() {
        flash.insert(image, ImageSizes::read(&build(image)?)?.flash_bytes);
    }
    Ok(costs(&flash))
}

/// The rows' costs from the images' flash sizes (rows whose images are missing are left out).
fn costs(flash: &std::collections::BTreeMap<Image, u64>) -> Vec<FeatureCost> {
    ROWS.iter()
        .filter_map(|r| {
            let (with, without) = (*flash.get(&r.with)?, *flash.get(&r.without)?);
            Some(FeatureCost {
                what: r.what,
                image: r.with.label(),
                baseline: r.without.label(),
                image_flash: with,
                baseline_flash: without,
                cost_bytes: with as i64 - without as i64,
            })
        })
        .collect()
}

/// The Markdown table of `costs` (or why they were not measured) appended to `s`.
pub fn table(s: &mut String, costs: &[FeatureCost], not_measured: Option<&str>) {
    use std::fmt::Write;
    if let Some(why) = not_measured {
        let _ = writeln!(s, "\nfeature costs ({TRIPLE}): not measured: {}", why.lines().next().unwrap_or(""));
        return;
    }
    let _ = writeln!(s, "\nfeature costs ({TRIPLE}, flash of examples/feature_cost.rs probe images, bytes):\n");
    let _ = writeln!(s, "| feature | image | baseline | image flash | baseline flash | cost |");
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|");
    for c in costs {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            c.what, c.image, c.baseline, c.image_flash, c.baseline_flash, c.cost_bytes
        );
    }
}

/// `cargo xtask feature-costs [--json]`: the feature costs alone.
pub fn run(json: bool) -> Result<(), String> {
    let costs = measure()?;
    if json {
        println!("{}", serde_json::to_string_pretty(&costs).map_err(|e| e.to_string())?);
    } else {
        let mut s = String::new();
        table(&mut s, &costs, None);
        print!("{s}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_image_is_built_once_and_the_default_features_last() {
        let all = images();
        assert_eq!(all.len(), 7);
        assert!(all.iter().take(6).all(|i| !i.default_features));
        assert_eq!(all[6], image("calibrate", true));
    }

    #[test]
    fn costs_are_differences_of_flash() {
        let flash = [(image("none", false), 1000), (image("blob", false), 3500), (image("storage", false), 7000)];
        let costs = costs(&flash.into_iter().collect());
        assert_eq!(costs.len(), 3);
        assert_eq!((costs[0].what, costs[0].cost_bytes), ("blob v2 encode + decode", 2500));
        assert_eq!(costs[1].cost_bytes, 6000);
        assert_eq!((costs[2].baseline.as_str(), costs[2].cost_bytes), ("blob", 3500));
    }

    #[test]
    fn the_table_has_a_row_per_cost_or_says_why_not() {
        let flash = [(image("none", false), 1000), (image("blob", false), 3500)];
        let mut s = String::new();
        table(&mut s, &costs(&flash.into_iter().collect()), None);
        assert!(s.contains("| blob v2 encode + decode | blob | none | 3500 | 1000 | 2500 |"), "{s}");
        let mut s = String::new();
        table(&mut s, &[], Some("build failed\ndetails"));
        assert!(s.contains("not measured: build failed") && !s.contains("details"), "{s}");
    }
}
