//! Builds the bench firmware (`examples/bench.rs`) for a target and runs `tools/cyclecount.py` on it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

use serde::{Deserialize, Serialize};

/// A firmware target of the report.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    /// Rust target triple.
    pub triple: &'static str,
    /// The core it stands for, for the tables.
    pub core: &'static str,
    /// `tools/cyclecount.py --cpu`: emulated core and its timing table.
    pub cpu: &'static str,
    /// Also built and sized: the QEMU example (an STM32F4 firmware, Cortex-M4F only).
    pub qemu_example: bool,
}

/// The report's targets; the first carries the budgets.
pub const TARGETS: [Target; 3] = [
    Target { triple: "thumbv7em-none-eabihf", core: "Cortex-M4F", cpu: "cortex-m4", qemu_example: true },
    Target { triple: "thumbv6m-none-eabi", core: "Cortex-M0+", cpu: "cortex-m0plus", qemu_example: false },
    Target { triple: "riscv32imc-unknown-none-elf", core: "RV32IMC", cpu: "rv32imc", qemu_example: false },
];

/// The cargo profile measured.
pub const PROFILE: &str = "release";

/// The bench image's measured functions (examples/bench.rs), in report order.
pub const FUNCTIONS: [&str; 7] = [
    "accumulate_fifo",
    "accumulate_sample",
    "apply_sample",
    "taga_generation",
    "lm",
    "initial_estimate",
    "full_calibration",
];

/// Seconds the emulator may run per image (a soft-float Cortex-M0+ image runs the longest).
const EMULATOR_TIMEOUT_S: u32 = 1800;

/// One statistic over the calls of a measured function.
#[derive(Debug, Clone, Deserialize)]
pub struct CallStat {
    /// Sum over the calls.
    pub total: u64,
    /// Mean per call.
    pub mean: f64,
    /// Largest call.
    pub max: u64,
}

/// `tools/cyclecount.py`'s figures of one measured function.
#[derive(Debug, Clone, Deserialize)]
pub struct FunctionRun {
    /// Calls during the run.
    pub calls: u64,
    /// Executed instructions.
    pub instructions: CallStat,
    /// Estimated cycles.
    pub cycles: CallStat,
    /// Deepest stack of one call, bytes.
    pub peak_stack_bytes: u64,
}

/// One function of the library calibration path and its code size.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CodeFunction {
    /// Symbol name, mangled.
    pub name: String,
    /// Bytes.
    pub size: u64,
    /// The crate the symbol belongs to.
    #[serde(rename = "crate")]
    pub krate: String,
}

/// The code reachable from the calibration path's entry points.
#[derive(Debug, Clone, Deserialize)]
pub struct StaticCode {
    /// Bytes in all.
    pub bytes: u64,
    /// Bytes by crate.
    pub by_crate: BTreeMap<String, u64>,
    /// Every function reached, largest first.
    pub functions: Vec<CodeFunction>,
}

/// `tools/cyclecount.py`'s output.
#[derive(Debug, Clone, Deserialize)]
pub struct Emulation {
    /// The bench's console output.
    pub stdout: String,
    /// The timing table used.
    pub cost_model: String,
    /// Measured functions by name.
    pub functions: BTreeMap<String, FunctionRun>,
    /// The library calibration path's code.
    pub static_code: StaticCode,
}

/// A built and emulated bench image.
pub struct Measured {
    /// The bench ELF file.
    pub bench_elf: PathBuf,
    /// The QEMU example's ELF file, when the target builds it.
    pub qemu_elf: Option<PathBuf>,
    /// The emulator's figures.
    pub emulation: Emulation,
}

/// The workspace root (the parent of this crate's manifest directory).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

fn output(cmd: &mut Command, what: &str) -> Result<Output, String> {
    cmd.output().map_err(|e| format!("{what}: cannot run {:?}: {e}", cmd.get_program()))
}

/// `rustc -V`.
pub fn toolchain() -> Result<String, String> {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    output(Command::new(rustc).arg("-V"), "rustc -V").map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
}

/// The executable of example `name` in cargo's `--message-format=json` output.
pub fn example_executable(messages: &[u8], name: &str) -> Option<PathBuf> {
    String::from_utf8_lossy(messages).lines().find_map(|line| {
        let v: serde_json::Value = serde_json::from_str(line).ok()?;
        let is_example = v["target"]["kind"].as_array()?.iter().any(|k| k == "example");
        (v["reason"] == "compiler-artifact" && is_example && v["target"]["name"] == name)
            .then(|| v["executable"].as_str().map(PathBuf::from))
            .flatten()
    })
}

/// Builds the release bench (and the QEMU example where it exists) for `target`; their ELF files.
pub fn build(target: &Target) -> Result<(PathBuf, Option<PathBuf>), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(workspace_root()).args(["build", "-p", "accelcal", "--quiet", "--message-format=json"]);
    cmd.args(["--profile", PROFILE, "--target", target.triple, "--example", "bench"]);
    if target.qemu_example {
        cmd.args(["--example", "qemu_calibrate"]);
    }
    let out = output(&mut cmd, "firmware build")?;
    if !out.status.success() {
        return Err(format!(
            "firmware build for {} failed (is the target installed? rustup target add {}):\n{}",
            target.triple,
            target.triple,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let elf = |name: &str| {
        example_executable(&out.stdout, name).ok_or_else(|| format!("cargo build did not report example {name}"))
    };
    Ok((elf("bench")?, if target.qemu_example { Some(elf("qemu_calibrate")?) } else { None }))
}

/// Starts `tools/cyclecount.py` on `bench_elf` (`PYTHON` selects the interpreter).
pub fn start_emulator(target: &Target, bench_elf: &Path) -> Result<Child, String> {
    let missing = crate::elf::missing_symbols(bench_elf, &FUNCTIONS)?;
    if !missing.is_empty() {
        return Err(format!("{}: the bench image lacks {}", bench_elf.display(), missing.join(", ")));
    }
    let root = workspace_root();
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    Command::new(&python)
        .current_dir(&root)
        .arg(root.join("tools/cyclecount.py"))
        .args(["--cpu", target.cpu, "--functions", &FUNCTIONS.join(","), "--timeout", &EMULATOR_TIMEOUT_S.to_string()])
        .arg(bench_elf)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run {python} tools/cyclecount.py: {e}"))
}

/// Waits for the emulator started by [`start_emulator`] and reads its figures.
pub fn finish_emulator(child: Child) -> Result<Emulation, String> {
    let out = child.wait_with_output().map_err(|e| format!("tools/cyclecount.py: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "tools/cyclecount.py failed (python3 -m pip install unicorn capstone pyelftools):\n{}{}",
            String::from_utf8_lossy(&out.stderr),
            String::from_utf8_lossy(&out.stdout)
        ));
    }
    serde_json::from_slice(&out.stdout).map_err(|e| format!("tools/cyclecount.py output: {e}"))
}

/// `key value` after `prefix` in the bench's console output.
pub fn stdout_field(stdout: &str, prefix: &str, key: &str) -> Option<u64> {
    let line = stdout.lines().find(|l| l.starts_with(prefix))?;
    let mut words = line.split_whitespace();
    words.find(|w| *w == key)?;
    words.next()?.trim_end_matches(',').parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bench_stdout_fields_are_found() {
        let out = "bench: lm iterations 9\nbench: full_calibration generations 150 evaluations 5741\n";
        assert_eq!(stdout_field(out, "bench: full_calibration", "generations"), Some(150));
        assert_eq!(stdout_field(out, "bench: lm", "iterations"), Some(9));
        assert_eq!(stdout_field(out, "bench: lm", "generations"), None);
    }

    #[test]
    fn example_executables_are_read_from_cargo_messages() {
        let messages = br#"{"reason":"compiler-artifact","target":{"kind":["lib"],"name":"accelcal"},"executable":null}
{"reason":"compiler-artifact","target":{"kind":["example"],"name":"bench"},"executable":"/t/examples/bench"}
{"reason":"build-finished","success":true}"#;
        assert_eq!(example_executable(messages, "bench"), Some(PathBuf::from("/t/examples/bench")));
        assert_eq!(example_executable(messages, "qemu_calibrate"), None);
    }

    #[test]
    fn the_budget_target_comes_first() {
        assert_eq!(TARGETS[0].triple, "thumbv7em-none-eabihf");
        assert!(TARGETS.iter().skip(1).all(|t| !t.qemu_example));
    }
}
