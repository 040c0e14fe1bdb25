//! `accelcal report`: flash, RAM and cycle figures of the firmware, checked against the budgets.
//!
//! 1. builds the release firmware (`examples/bench.rs` and `examples/qemu_calibrate.rs`) for
//!    [`TARGET`] with cargo;
//! 2. runs `tools/cyclecount.py` on the bench image: an instruction-set emulator (Unicorn) runs it from
//!    reset and counts the instructions of every call of the [`FUNCTIONS`], priced in Cortex-M4 cycles
//!    from the TRM's timing table, and measures each call's stack by painting;
//! 3. reads the section headers of both ELF files for the flash and static RAM sizes;
//! 4. prints a Markdown table, or JSON with `--json`, and compares every figure with its [`BUDGETS`]
//!    entry. `--check` fails only on the budgets marked `enforced`; the others are goals, reported with
//!    how far they are missed.
//!
//! Needs `python3` with `unicorn`, `capstone` and `pyelftools` (`python3 -m pip install unicorn capstone
//! pyelftools`; `PYTHON` selects the interpreter) and the target (`rustup target add
//! thumbv7em-none-eabihf`).

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::{Value, json};

/// The firmware target.
pub const TARGET: &str = "thumbv7em-none-eabihf";
/// The cargo profile measured.
pub const PROFILE: &str = "release";
/// The bench image's measured functions (examples/bench.rs), in report order.
pub const FUNCTIONS: [&str; 6] =
    ["accumulate_sample", "apply_sample", "taga_generation", "lm", "initial_estimate", "full_calibration"];
/// How the cycles are obtained, and their error.
pub const METHOD: &str = "unicorn + Cortex-M4 timing table (+-10-30 % vs silicon)";

/// One budget (a goal of the "Firmware" issue): a figure of the report and its upper limit.
#[derive(Debug, Clone, Copy)]
pub struct Budget {
    /// Key in the JSON `budgets` and `within_budget` objects.
    pub key: &'static str,
    /// What is limited, for the table.
    pub what: &'static str,
    /// Upper limit, inclusive.
    pub limit: u64,
    /// Unit of `limit`.
    pub unit: &'static str,
    /// `--check` fails when this budget is exceeded. Only budgets met today are enforced, so that CI
    /// guards them; a missed goal is reported with its overshoot and enforced once it is met.
    pub enforced: bool,
    /// Regression ceiling, same unit: the figure measured when it was last lowered plus about 10 %.
    /// `--check` always fails above it, so CI catches a regression while the goal is still missed.
    pub ceiling: u64,
}

/// The budgets, goals of the firmware issue (24 poses, the bench's device population).
pub const BUDGETS: [Budget; 6] = [
    Budget {
        key: "full_calibration_cycles",
        what: "full 24-pose calibration",
        limit: 2_000_000,
        unit: "cycles",
        enforced: true,
        ceiling: 2_000_000,
    },
    Budget { key: "lm_cycles", what: "LM alone", limit: 100_000, unit: "cycles", enforced: true, ceiling: 100_000 },
    Budget {
        key: "accumulate_cycles_per_sample",
        what: "accumulate one sample",
        limit: 30,
        unit: "cycles",
        enforced: false,
        ceiling: 107,
    },
    Budget {
        key: "apply_cycles_per_sample",
        what: "apply one sample",
        limit: 25,
        unit: "cycles",
        enforced: false,
        ceiling: 31,
    },
    Budget {
        key: "library_flash_bytes",
        what: "library calibration path, flash",
        limit: 16 * 1024,
        unit: "bytes",
        enforced: false,
        ceiling: 33_200,
    },
    Budget {
        key: "solve_ram_bytes",
        what: "RAM: static + peak stack of the solve",
        limit: 4 * 1024,
        unit: "bytes",
        enforced: true,
        ceiling: 3_940,
    },
];

/// Library functions listed in the flash breakdown.
pub const TOP_FUNCTIONS: usize = 10;

/// Runs the report; prints it (Markdown, or JSON when `json`). Returns `Ok(false)` when `check` is set
/// and an enforced budget is exceeded, `Err` when something could not be built, run or read.
pub fn run(json: bool, check: bool) -> Result<bool, String> {
    let report = measure()?;
    if json {
        crate::output::write_stdout(&format!(
            "{}\n",
            serde_json::to_string_pretty(&report.json).map_err(|e| e.to_string())?
        ));
    } else {
        crate::output::write_stdout(&report.markdown);
    }
    let failed = exceeded(&BUDGETS, &report.within, &report.measured);
    if check && !failed.is_empty() {
        eprintln!("accelcal report: enforced budget exceeded: {}", failed.join(", "));
        return Ok(false);
    }
    Ok(true)
}

/// The budgets `--check` fails on: enforced ones that `within` (budget key to "within budget") marks
/// exceeded or does not mention, and any whose `measured` figure is above its regression ceiling (or
/// missing).
fn exceeded(
    budgets: &[Budget],
    within: &std::collections::BTreeMap<&'static str, bool>,
    measured: &std::collections::BTreeMap<&'static str, u64>,
) -> Vec<&'static str> {
    budgets
        .iter()
        .filter(|b| {
            let goal_missed = b.enforced && !within.get(b.key).copied().unwrap_or(false);
            let regressed = measured.get(b.key).is_none_or(|m| *m > b.ceiling);
            goal_missed || regressed
        })
        .map(|b| b.key)
        .collect()
}

/// A measured report.
pub struct Report {
    /// The JSON document (`--json`).
    pub json: Value,
    /// The Markdown rendering.
    pub markdown: String,
    /// Budget key to "within budget".
    pub within: std::collections::BTreeMap<&'static str, bool>,
    /// Budget key to the measured figure.
    pub measured: std::collections::BTreeMap<&'static str, u64>,
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// The executable of example `name` in cargo's `--message-format=json` output.
fn example_executable(messages: &[u8], name: &str) -> Option<PathBuf> {
    String::from_utf8_lossy(messages).lines().find_map(|line| {
        let v: Value = serde_json::from_str(line).ok()?;
        let is_example = v["target"]["kind"].as_array()?.iter().any(|k| k == "example");
        (v["reason"] == "compiler-artifact" && is_example && v["target"]["name"] == name)
            .then(|| v["executable"].as_str().map(PathBuf::from))
            .flatten()
    })
}

fn command_output(cmd: &mut Command, what: &str) -> Result<std::process::Output, String> {
    cmd.output().map_err(|e| format!("{what}: cannot run {:?}: {e}", cmd.get_program()))
}

/// Builds the firmware, runs the emulator and reads the ELF files.
pub fn measure() -> Result<Report, String> {
    let root = workspace_root();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut build = Command::new(&cargo);
    build.current_dir(&root).args([
        "build",
        "-p",
        "accelcal",
        "--quiet",
        "--message-format=json",
        "--release",
        "--target",
        TARGET,
        "--example",
        "bench",
        "--example",
        "qemu_calibrate",
    ]);
    let out = command_output(&mut build, "firmware build")?;
    if !out.status.success() {
        return Err(format!(
            "firmware build failed (is the target installed? rustup target add {TARGET}):\n{}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let elf = |name: &str| {
        example_executable(&out.stdout, name).ok_or_else(|| format!("cargo build did not report example {name}"))
    };
    let (bench_elf, qemu_elf) = (elf("bench")?, elf("qemu_calibrate")?);

    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    let mut emulate = Command::new(&python);
    emulate.current_dir(&root).arg(root.join("tools/cyclecount.py")).arg(&bench_elf);
    let out = command_output(&mut emulate, "tools/cyclecount.py")?;
    if !out.status.success() {
        return Err(format!(
            "tools/cyclecount.py failed (python3 -m pip install unicorn capstone pyelftools):\n{}{}",
            String::from_utf8_lossy(&out.stderr),
            String::from_utf8_lossy(&out.stdout)
        ));
    }
    let emu: Value = serde_json::from_slice(&out.stdout).map_err(|e| format!("tools/cyclecount.py output: {e}"))?;

    let bench = Elf::read(&bench_elf)?;
    let qemu = Elf::read(&qemu_elf)?;
    let toolchain =
        command_output(Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into())).arg("-V"), "rustc -V")
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())?;
    Ok(assemble(&emu, &bench, &qemu, &toolchain))
}

fn get_u64(v: &Value, path: &[&str]) -> u64 {
    let mut v = v;
    for p in path {
        v = &v[*p];
    }
    v.as_f64().map_or(0, |x| x.round() as u64)
}

/// `key value` after `prefix` in the bench's semihosting output.
fn stdout_field(stdout: &str, prefix: &str, key: &str) -> Option<u64> {
    let line = stdout.lines().find(|l| l.starts_with(prefix))?;
    let mut words = line.split_whitespace();
    words.find(|w| *w == key)?;
    words.next()?.trim_end_matches(',').parse().ok()
}

fn assemble(emu: &Value, bench: &Elf, qemu: &Elf, toolchain: &str) -> Report {
    let f = |name: &str, what: &str| get_u64(emu, &["functions", name, what, "mean"]);
    let instructions: serde_json::Map<String, Value> =
        FUNCTIONS.iter().map(|n| ((*n).to_string(), json!(f(n, "instructions")))).collect();
    let cycles: serde_json::Map<String, Value> =
        FUNCTIONS.iter().map(|n| ((*n).to_string(), json!(f(n, "cycles")))).collect();
    let calls: serde_json::Map<String, Value> =
        FUNCTIONS.iter().map(|n| ((*n).to_string(), json!(get_u64(emu, &["functions", n, "calls"])))).collect();
    let max_cycles: serde_json::Map<String, Value> =
        FUNCTIONS.iter().map(|n| ((*n).to_string(), json!(get_u64(emu, &["functions", n, "cycles", "max"])))).collect();
    let stdout = emu["stdout"].as_str().unwrap_or("");
    let population = stdout_field(stdout, "bench: sizes", "population");
    let apply_batch = stdout_field(stdout, "bench: apply", "samples_per_call").unwrap_or(1).max(1);
    let apply_per_sample = f("apply_sample", "cycles").div_ceil(apply_batch);
    let top_functions: Vec<Value> = emu["static_code"]["functions"]
        .as_array()
        .map(|v| v.iter().take(TOP_FUNCTIONS).cloned().collect())
        .unwrap_or_default();
    let generations = stdout_field(stdout, "bench: full_calibration", "generations");
    let lm_iterations = stdout_field(stdout, "bench: lm", "iterations");
    let accumulator = stdout_field(stdout, "bench: sizes", "accumulator");
    let ga_state = stdout_field(stdout, "bench: sizes", "ga");
    let library = get_u64(emu, &["static_code", "bytes"]);
    let peak_stack = get_u64(emu, &["functions", "full_calibration", "peak_stack_bytes"]);
    let static_ram = bench.static_ram();
    let measured = [
        f("full_calibration", "cycles"),
        f("lm", "cycles"),
        f("accumulate_sample", "cycles"),
        apply_per_sample,
        library,
        static_ram + peak_stack,
    ];
    let within: std::collections::BTreeMap<&'static str, bool> =
        BUDGETS.iter().zip(measured).map(|(b, m)| (b.key, m <= b.limit)).collect();
    let budgets: serde_json::Map<String, Value> = BUDGETS
        .iter()
        .zip(measured)
        .map(|(b, m)| {
            let entry = json!({"limit": b.limit, "unit": b.unit, "measured": m, "enforced": b.enforced,
                               "regression_ceiling": b.ceiling});
            (b.key.to_string(), entry)
        })
        .collect();
    let enforced: Vec<&str> = BUDGETS.iter().filter(|b| b.enforced).map(|b| b.key).collect();
    let json = json!({
        "instructions": instructions,
        "cycles": cycles,
        "calls": calls,
        "max_cycles": max_cycles,
        "flash_bytes": {
            "library": library,
            "library_by_crate": emu["static_code"]["by_crate"],
            "library_top_functions": top_functions,
            "qemu_example": qemu.flash(),
            "bench_example": bench.flash(),
        },
        "ram_bytes": {
            "static": static_ram,
            "peak_stack": peak_stack,
            "accumulator": accumulator,
            "ga_state": ga_state,
            "peak_stack_by_function": FUNCTIONS.iter()
                .map(|n| ((*n).to_string(), json!(get_u64(emu, &["functions", n, "peak_stack_bytes"]))))
                .collect::<serde_json::Map<_, _>>(),
        },
        "budgets": budgets,
        "within_budget": within,
        "enforced": enforced,
        "target": TARGET,
        "profile": PROFILE,
        "toolchain": toolchain,
        "population": population,
        "apply_samples_per_call": apply_batch,
        "apply_cycles_per_sample": apply_per_sample,
        "generations": generations,
        "lm_iterations": lm_iterations,
        "branch_penalty_cycles": emu["branch_penalty"],
        "method": METHOD,
    });
    let markdown = markdown(&json, &measured, &within);
    let measured = BUDGETS.iter().zip(measured).map(|(b, m)| (b.key, m)).collect();
    Report { json, markdown, within, measured }
}

fn status(measured: u64, b: &Budget, ok: bool) -> String {
    let tag = if b.enforced { ", enforced" } else { "" };
    if ok {
        format!("met{tag}")
    } else {
        format!("MISSED by {} ({:.1}x){tag}", measured - b.limit, measured as f64 / b.limit as f64)
    }
}

/// The largest functions of the library calibration path, as a Markdown table.
fn top_functions_table(s: &mut String, flash: &Value) {
    use std::fmt::Write;
    let _ = writeln!(s, "\nlargest functions of the library calibration path (flash):\n");
    let _ = writeln!(s, "| bytes | crate | function |");
    let _ = writeln!(s, "|---:|---|---|");
    for f in flash["library_top_functions"].as_array().map(Vec::as_slice).unwrap_or_default() {
        let name = f["name"].as_str().unwrap_or("");
        let _ = writeln!(s, "| {} | {} | {} |", f["size"], f["crate"].as_str().unwrap_or(""), demangled(name));
    }
}

fn markdown(j: &Value, measured: &[u64; 6], within: &std::collections::BTreeMap<&'static str, bool>) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let budget_cell = |key: &str| -> String {
        BUDGETS
            .iter()
            .zip(measured)
            .find(|(b, _)| b.key == key)
            .map(|(b, m)| {
                format!("<= {} {} | {}", b.limit, b.unit, status(*m, b, within.get(b.key).copied().unwrap_or(false)))
            })
            .unwrap_or_else(|| " | ".into())
    };
    let _ = writeln!(
        s,
        "accelcal report: {}, {} profile, {}; population {}, {} generations",
        j["target"].as_str().unwrap_or(""),
        j["profile"].as_str().unwrap_or(""),
        j["toolchain"].as_str().unwrap_or(""),
        j["population"],
        j["generations"]
    );
    let _ = writeln!(
        s,
        "method: {}; taken branch +{} cycle, flash wait states not modelled\n",
        j["method"].as_str().unwrap_or(""),
        j["branch_penalty_cycles"]
    );
    let _ = writeln!(s, "| measure | calls | instructions | cycles | budget | status |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---|");
    let apply = format!("apply one sample (per sample of a {}-sample call)", j["apply_samples_per_call"]);
    let generation = format!("one TAGA generation, 24 poses, pop. {} (mean)", j["population"]);
    let rows = [
        ("accumulate_sample", "accumulate one sample (mean per call)", Some("accumulate_cycles_per_sample")),
        ("apply_sample", apply.as_str(), Some("apply_cycles_per_sample")),
        ("taga_generation", generation.as_str(), None),
        ("lm", "LM alone from the coarse start", Some("lm_cycles")),
        ("initial_estimate", "initial estimate: robust ellipsoid fit, 24 poses", None),
        ("full_calibration", "full calibration: coarse + TAGA + LM + verdict", Some("full_calibration_cycles")),
    ];
    for (k, what, budget) in rows {
        let cycles = if k == "apply_sample" { &j["apply_cycles_per_sample"] } else { &j["cycles"][k] };
        let _ = writeln!(
            s,
            "| {what} | {} | {} | {} | {} |",
            j["calls"][k],
            j["instructions"][k],
            cycles,
            budget.map_or_else(|| " | ".to_string(), budget_cell)
        );
    }
    let flash = &j["flash_bytes"];
    let ram = &j["ram_bytes"];
    let _ = writeln!(
        s,
        "| flash: library calibration path ({}) | | | {} B | {} |",
        crates(&flash["library_by_crate"]),
        flash["library"],
        budget_cell("library_flash_bytes")
    );
    let _ =
        writeln!(s, "| flash: qemu_calibrate example (text + rodata + data) | | | {} B | | |", flash["qemu_example"]);
    let _ = writeln!(s, "| RAM: static (.data + .bss) of the bench image | | | {} B | | |", ram["static"]);
    let _ = writeln!(
        s,
        "| RAM: peak stack of full_calibration (the GA state, {} B, lives in it) | | | {} B | | |",
        ram["ga_state"], ram["peak_stack"]
    );
    let _ = writeln!(
        s,
        "| RAM: peak stack of the initial estimate (ellipsoid fit; inside the solve's) | | | {} B | | |",
        ram["peak_stack_by_function"]["initial_estimate"]
    );
    let _ = writeln!(
        s,
        "| RAM: static + peak stack of the solve | | | {} B | {} |",
        measured[5],
        budget_cell("solve_ram_bytes")
    );
    let _ = writeln!(
        s,
        "| RAM: the caller's Accumulator<i16, 24, 32> (holds the poses; not in the budget) | | | {} B | | |",
        ram["accumulator"]
    );
    top_functions_table(&mut s, flash);
    let _ = writeln!(
        s,
        "\nother targets: {} and {} build the library (CI); their flash and cycles are not measured here: the \
         bench image is an STM32F4 (Cortex-M4F) firmware, and tools/cyclecount.py emulates Thumb-2 only.",
        OTHER_TARGETS[0], OTHER_TARGETS[1]
    );
    let enforced: Vec<&str> = BUDGETS.iter().filter(|b| b.enforced).map(|b| b.key).collect();
    let _ = writeln!(
        s,
        "\nenforced by --check: goals {}; regression ceilings (today's figure + ~10 %) on all: {}",
        if enforced.is_empty() { "none (every budget is still a goal)".to_string() } else { enforced.join(", ") },
        BUDGETS.iter().map(|b| format!("{} <= {} {}", b.key, b.ceiling, b.unit)).collect::<Vec<_>>().join(", ")
    );
    s
}

/// The other library targets CI builds (Cortex-M0+, soft float; RISC-V RV32IMC).
pub const OTHER_TARGETS: [&str; 2] = ["thumbv6m-none-eabi", "riscv32imc-unknown-none-elf"];

/// `accelcal::solve::normal_equations` for a legacy-mangled `_ZN...17h<hash>E` symbol; other names as
/// they are.
fn demangled(symbol: &str) -> String {
    let Some(mut rest) = symbol.strip_prefix("_ZN") else { return symbol.to_string() };
    let mut parts = Vec::new();
    while let Some(end) = rest.find(|c: char| !c.is_ascii_digit()) {
        let Ok(len) = rest[..end].parse::<usize>() else { break };
        let Some(part) = rest.get(end..end + len) else { break };
        if !(part.starts_with('h') && part.len() == 17) {
            parts.push(part.replace("$LT$", "<").replace("$GT$", ">").replace("$C$", ",").replace("$u20$", " "));
        }
        rest = &rest[end + len..];
    }
    if parts.is_empty() { symbol.to_string() } else { parts.join("::") }
}

fn crates(by_crate: &Value) -> String {
    let mut v: Vec<(String, u64)> = by_crate
        .as_object()
        .map(|m| m.iter().map(|(k, v)| (k.clone(), v.as_u64().unwrap_or(0))).collect())
        .unwrap_or_default();
    v.sort_by_key(|(_, n)| std::cmp::Reverse(*n));
    v.iter().map(|(k, n)| format!("{k} {n}")).collect::<Vec<_>>().join(", ")
}

/// The section headers of a 32-bit little-endian ELF file (all the report needs).
pub struct Elf {
    /// `(name, type, flags, address, size)` per section.
    pub sections: Vec<(String, u32, u32, u32, u32)>,
}

const SHT_NOBITS: u32 = 8;
const SHF_WRITE: u32 = 0x1;
const SHF_ALLOC: u32 = 0x2;

impl Elf {
    /// Reads `path`.
    pub fn read(path: &Path) -> Result<Self, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Parses the section headers of an ELF32 little-endian image.
    pub fn parse(b: &[u8]) -> Result<Self, String> {
        if b.len() < 52 || &b[..4] != b"\x7fELF" || b[4] != 1 || b[5] != 1 {
            return Err("not a 32-bit little-endian ELF file".into());
        }
        let u16_at = |o: usize| b.get(o..o + 2).map(|s| u16::from_le_bytes([s[0], s[1]]));
        let u32_at = |o: usize| b.get(o..o + 4).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]));
        let bad = || "truncated section headers".to_string();
        let shoff = u32_at(0x20).ok_or_else(bad)? as usize;
        let shentsize = u16_at(0x2E).ok_or_else(bad)? as usize;
        let shnum = u16_at(0x30).ok_or_else(bad)? as usize;
        let shstrndx = u16_at(0x32).ok_or_else(bad)? as usize;
        let header = |i: usize, field: usize| u32_at(shoff + i * shentsize + 4 * field).ok_or_else(bad);
        let strtab = header(shstrndx, 4)? as usize;
        let mut sections = Vec::with_capacity(shnum);
        for i in 0..shnum {
            let name_off = strtab + header(i, 0)? as usize;
            let name = b
                .get(name_off..)
                .and_then(|s| s.split(|&c| c == 0).next())
                .map(|s| String::from_utf8_lossy(s).into_owned())
                .unwrap_or_default();
            sections.push((name, header(i, 1)?, header(i, 2)?, header(i, 3)?, header(i, 5)?));
        }
        Ok(Self { sections })
    }

    /// Bytes written to flash: every allocated section with contents (vector table, text, rodata, and
    /// the initial values of .data).
    pub fn flash(&self) -> u64 {
        self.sections.iter().filter(|s| s.2 & SHF_ALLOC != 0 && s.1 != SHT_NOBITS).map(|s| u64::from(s.4)).sum()
    }

    /// Static RAM: every allocated writable section (.data, .bss, .uninit).
    pub fn static_ram(&self) -> u64 {
        self.sections.iter().filter(|s| s.2 & SHF_ALLOC != 0 && s.2 & SHF_WRITE != 0).map(|s| u64::from(s.4)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal ELF32 with a null section, .text (alloc, 100 bytes), .bss (alloc+write, nobits, 40) and
    /// .shstrtab.
    fn tiny_elf() -> Vec<u8> {
        let names = b"\0.text\0.bss\0.shstrtab\0";
        let shoff = 52 + names.len();
        let mut b = vec![0u8; 52];
        b[..6].copy_from_slice(b"\x7fELF\x01\x01");
        b[0x20..0x24].copy_from_slice(&(shoff as u32).to_le_bytes());
        b[0x2E..0x30].copy_from_slice(&40u16.to_le_bytes());
        b[0x30..0x32].copy_from_slice(&4u16.to_le_bytes());
        b[0x32..0x34].copy_from_slice(&3u16.to_le_bytes());
        b.extend_from_slice(names);
        let mut sh = |name: u32, ty: u32, flags: u32, addr: u32, off: u32, size: u32| {
            for v in [name, ty, flags, addr, off, size, 0, 0, 4, 0] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        };
        sh(0, 0, 0, 0, 0, 0);
        sh(1, 1, SHF_ALLOC | 0x4, 0x0800_0000, 0, 100);
        sh(7, SHT_NOBITS, SHF_ALLOC | SHF_WRITE, 0x2000_0000, 0, 40);
        sh(12, 3, 0, 0, 52, names.len() as u32);
        b
    }

    #[test]
    fn elf_sections_give_flash_and_static_ram() {
        let elf = Elf::parse(&tiny_elf()).unwrap();
        let names: Vec<&str> = elf.sections.iter().map(|s| s.0.as_str()).collect();
        assert_eq!(names, ["", ".text", ".bss", ".shstrtab"]);
        assert_eq!(elf.flash(), 100);
        assert_eq!(elf.static_ram(), 40);
    }

    #[test]
    fn non_elf_input_is_an_error() {
        assert!(Elf::parse(b"not an elf").is_err());
        let mut truncated = tiny_elf();
        truncated.truncate(60);
        assert!(Elf::parse(&truncated).is_err());
    }

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
    fn check_fails_only_on_enforced_budgets() {
        let budget = |key, enforced| Budget { key, what: "", limit: 1, unit: "", enforced, ceiling: 10 };
        let budgets = [budget("a", true), budget("b", false), budget("c", true)];
        let within = [("a", true), ("b", false), ("c", false)].into_iter().collect();
        let measured = [("a", 1), ("b", 5), ("c", 5)].into_iter().collect();
        assert_eq!(exceeded(&budgets, &within, &measured), ["c"]);
        // A budget without a measurement is exceeded when enforced, and above every ceiling.
        assert_eq!(exceeded(&budgets, &Default::default(), &measured), ["a", "c"]);
        // A goal that is not enforced still fails above its regression ceiling.
        let regressed = [("a", 1), ("b", 11), ("c", 5)].into_iter().collect();
        assert_eq!(exceeded(&budgets, &within, &regressed), ["b", "c"]);
    }

    #[test]
    fn legacy_symbols_are_demangled() {
        assert_eq!(
            demangled("_ZN8accelcal5solve16normal_equations17h7da68b062d8ddf8cE"),
            "accelcal::solve::normal_equations"
        );
        assert_eq!(
            demangled("_ZN8accelcal2ga19Ga$LT$R$C$_$C$_$GT$6mutate17hdd9768c997acc952E"),
            "accelcal::ga::Ga<R,_,_>::mutate"
        );
        assert_eq!(demangled("__aeabi_memcpy4"), "__aeabi_memcpy4");
    }

    #[test]
    fn every_budget_has_a_measure_and_a_distinct_key() {
        let mut keys: Vec<&str> = BUDGETS.iter().map(|b| b.key).collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), BUDGETS.len());
    }
}
