//! Size and cycle benchmark image for `cargo xtask report`: the library's hot paths in never-inlined
//! functions with stable symbol names (`examples/common/bench_core.rs`, target-independent), and a thin
//! entry per target that gives the core a console and an exit:
//!
//! - ARM (`thumbv7em-none-eabihf` Cortex-M4F, `thumbv6m-none-eabi` Cortex-M0+): cortex-m-rt, semihosting
//!   output and exit; runs in QEMU (`cargo run --release --target thumbv7em-none-eabihf --example bench`).
//! - RISC-V (`riscv32imc-unknown-none-elf`): a minimal `_start` (stack, .bss, .data) and the linker script
//!   `examples/riscv/link.x`; output to a 16550 UART at 0x1000_0000 and exit through the SiFive test device at
//!   0x10_0000, the `qemu-system-riscv32 -M virt -bios none` layout.
//! - the host: the same core, printing to stdout (`cargo run --release --example bench`).
//!
//! `tools/cyclecount.py` runs the firmware images in an instruction-set emulator and counts the
//! instructions and estimated cycles of every call of the measured functions; the xtask turns that into
//! the report.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[path = "common/bench_core.rs"]
mod bench_core;
#[path = "common/sim_sensor.rs"]
mod sim_sensor;

#[cfg(not(target_os = "none"))]
fn main() {
    bench_core::run(&mut host::Stdout)
}

#[cfg(not(target_os = "none"))]
mod host {
    /// The host's standard output.
    pub struct Stdout;

    impl core::fmt::Write for Stdout {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            print!("{s}");
            Ok(())
        }
    }

    impl crate::bench_core::Console for Stdout {
        fn exit(&mut self, success: bool) -> ! {
            std::process::exit(if success { 0 } else { 1 })
        }
    }
}

#[cfg(all(target_os = "none", target_arch = "arm"))]
mod arm {
    use cortex_m_semihosting::{debug, hio};
    use panic_semihosting as _;
    // Links the device interrupt table that cortex-m-rt's `device` feature asks for on the Cortex-M4F (see
    // examples/qemu_calibrate.rs); no interrupt is enabled. The Cortex-M0+ build has no device crate.
    #[cfg(target_has_atomic = "32")]
    use stm32f4xx_hal as _;

    /// Semihosting standard output (the host's terminal under QEMU or a debug probe).
    struct Semihosting(Option<hio::HostStream>);

    impl core::fmt::Write for Semihosting {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            self.0.as_mut().map_or(Ok(()), |out| out.write_str(s))
        }
    }

    impl crate::bench_core::Console for Semihosting {
        fn exit(&mut self, success: bool) -> ! {
            debug::exit(if success { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
            #[allow(clippy::empty_loop)]
            loop {}
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        crate::bench_core::run(&mut Semihosting(hio::hstdout().ok()))
    }
}

#[cfg(all(target_os = "none", target_arch = "riscv32"))]
mod riscv {
    use core::fmt::Write;

    /// Transmit register of the 16550 UART (QEMU `virt`'s UART0).
    const UART_THR: usize = 0x1000_0000;
    /// The SiFive test device (QEMU `virt`): 0x5555 ends the run with success, `code << 16 | 0x3333` fails.
    const TEST_DEVICE: usize = 0x10_0000;

    // Reset: stack pointer, .bss cleared, .data copied from its load address, then `bench_main`.
    core::arch::global_asm!(
        ".section .text.start, \"ax\"",
        ".global _start",
        "_start:",
        ".option push",
        ".option norelax",
        "    la sp, _stack_top",
        ".option pop",
        "    la t0, __sbss",
        "    la t1, __ebss",
        "1:  bgeu t0, t1, 2f",
        "    sw zero, 0(t0)",
        "    addi t0, t0, 4",
        "    j 1b",
        "2:  la t0, __sdata",
        "    la t1, __edata",
        "    la t2, __sidata",
        "3:  bgeu t0, t1, 4f",
        "    lw t3, 0(t2)",
        "    sw t3, 0(t0)",
        "    addi t0, t0, 4",
        "    addi t2, t2, 4",
        "    j 3b",
        "4:  call bench_main",
        "5:  j 5b",
    );

    /// The UART and the test device.
    struct Uart;

    impl Write for Uart {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for byte in s.bytes() {
                // SAFETY: UART_THR is the UART's transmit register on the `virt` layout this image is linked for.
                unsafe { core::ptr::write_volatile(UART_THR as *mut u8, byte) };
            }
            Ok(())
        }
    }

    impl crate::bench_core::Console for Uart {
        fn exit(&mut self, success: bool) -> ! {
            let code: u32 = if success { 0x5555 } else { 1 << 16 | 0x3333 };
            // SAFETY: TEST_DEVICE is the SiFive test device's register on the `virt` layout.
            unsafe { core::ptr::write_volatile(TEST_DEVICE as *mut u32, code) };
            #[allow(clippy::empty_loop)]
            loop {}
        }
    }

    #[unsafe(no_mangle)]
    extern "C" fn bench_main() -> ! {
        crate::bench_core::run(&mut Uart)
    }

    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        let _ = writeln!(Uart, "bench: panic: {info}");
        crate::bench_core::Console::exit(&mut Uart, false)
    }
}
