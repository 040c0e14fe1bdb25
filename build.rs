//! Linker set-up for the firmware examples (`examples/*.rs`), and nothing else.
//!
//! Only when the target is bare metal (`target_os = "none"`, e.g. `thumbv7em-none-eabihf`): copies
//! `memory.x` to `OUT_DIR` and passes `-L OUT_DIR -Tlink.x --nmagic` to the linker, for this package's
//! examples only; with the `defmt` feature also `-Tdefmt.x` (see below). Link arguments rather than `rustc-link-search`, which would leak this crate's
//! `memory.x` into the link of every firmware that depends on the library. The host build is untouched,
//! and nothing relies on `RUSTFLAGS` (which would replace `.cargo/config.toml`'s flags).

use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=memory.x");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let Some(out) = std::env::var_os("OUT_DIR").map(PathBuf::from) else {
        panic!("OUT_DIR is not set: build.rs must run under cargo");
    };
    if let Err(e) = std::fs::copy("memory.x", out.join("memory.x")) {
        panic!("cannot copy memory.x to {}: {e}", out.display());
    }
    // RISC-V has no cortex-m-rt: the bench image's own linker script is its `link.x`.
    println!("cargo:rerun-if-changed=examples/riscv/link.x");
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("riscv32")
        && let Err(e) = std::fs::copy("examples/riscv/link.x", out.join("link.x"))
    {
        panic!("cannot copy examples/riscv/link.x to {}: {e}", out.display());
    }
    println!("cargo:rustc-link-arg-examples=-L{}", out.display());
    println!("cargo:rustc-link-arg-examples=-Tlink.x");
    println!("cargo:rustc-link-arg-examples=--nmagic");
    // defmt's linker script (`defmt.x`, on the search path from defmt's own build script) places the
    // interned log strings. Only with the `defmt` feature, which the defmt example requires; the other
    // examples then link it too and stay defmt-free (its `EXTERN` symbols only pull a logger in when
    // one is linked, and nothing references them otherwise).
    if std::env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg-examples=-Tdefmt.x");
    }
}
