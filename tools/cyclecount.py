#!/usr/bin/env python3
"""Instruction and estimated cycle counts of the bench image's functions (examples/bench.rs), per core.

--cpu cortex-m4 (default; thumbv7em-none-eabihf), cortex-m0plus (thumbv6m-none-eabi) or rv32imc
(riscv32imc-unknown-none-elf). Runs the firmware ELF in the Unicorn emulator from its reset (the ARM vector
table; the RISC-V ELF entry) to its exit (ARM semihosting; RISC-V the SiFive test device at 0x100000, output
to the UART at 0x10000000, QEMU `virt`'s layout). Every call of a function named in --functions is measured
from its first instruction to its return: the executed instructions are counted per translated block, each
instruction is classified with Capstone and priced from the core's timing table.

Cortex-M4 (Thumb-2, M-profile, with the FPU that cortex-m-rt's Reset handler enables), from the ARM
Cortex-M4 Technical Reference Manual (r0p1, table 3-1):

  ALU, shifts, bit fields, MUL, long multiplies, IT ........ 1       MLA, MLS ...................... 2
  LDR/STR (single) ......................................... 2, or 1 when it directly follows another
                                                              single load/store (pipelined)
  LDRD/STRD ................................................ 3       LDM/STM/PUSH/POP ....... 1 + N
  SDIV/UDIV ................................................ 7 (2..12, data dependent; mid value)
  B/BL/BX/BLX/CBZ/CBNZ, POP {pc}, LDR pc ............... 1 (+ P when taken)      TBB/TBH ... 2 (+ P)
  VADD/VSUB/VMUL/VNMUL/VNEG/VABS/VCMP/VCVT/VMOV/VMRS ....... 1       VMLA/VMLS/VFMA/VFMS ....... 3
  VDIV/VSQRT .............................................. 14       VLDR/VSTR ................. 2
  VLDM/VSTM/VPUSH/VPOP .................................... 1 + N (32-bit words)

P, the pipeline refill of a taken branch, is 1..3 on silicon; --branch-penalty sets it (default 1, the
zero-wait-state case). Flash wait states, bus contention, load-use and FPU register hazards, and IT
folding are not modelled, so the cycle figures are an estimate, typically within 10-30 % of a real
Cortex-M4F running from zero-wait-state memory (or from flash behind the STM32 ART accelerator).

Cortex-M0+ (ARMv6-M, no FPU: floats are compiler_builtins calls, emulated and priced like the rest; Unicorn
emulates the M profile with Thumb-2, so every executed instruction is checked to be ARMv6-M: 16 bits wide, or
one of BL, MSR, MRS, DMB, DSB, ISB), from the Cortex-M0+ TRM (r0p1, table 3-1, a
2-stage pipeline): ALU, shifts, extends, MULS ... 1 (the single-cycle multiplier option, which the common
parts have: RP2040, STM32G0/L0, SAMD21; the small 32-cycle one would cost far more); LDR/STR ... 2; LDM/STM/
PUSH/POP ... 1 + N; B/BX/BLX ... 1 (+ P when taken, P = 1: 2 cycles taken); BL ... 2 + P = 3; POP {pc} ...
2 + N + P. Zero-wait-state memory.

RV32IMC (riscv32imc-unknown-none-elf): a simple model, not a chip: ALU, LUI/AUIPC, MUL/MULH ... 1; loads 2;
stores 1; conditional branches 1 (+ P when taken), JAL/JALR 1 + P, P = 2 (3 cycles taken); DIV/DIVU/REM/REMU
34. Zero-wait-state memory; cores range from a 2-stage pipeline (taken branch 2-3) to multi-issue.

The stack of every measured call is measured by painting the free RAM below the stack pointer at its
entry (from the end of .bss up) with a pattern and finding, at its return, the lowest byte overwritten.

Statically, the code a firmware links for these functions is found by walking the call graph from their
symbols (direct BL/B targets in the disassembly; on RISC-V JAL, branches and AUIPC + JALR pairs) and summing
the symbol sizes reached, by crate.

Cross-check: the instruction counts equal, call by call, those of an independent QEMU 7.2 run of the same
image (`qemu-system-arm -M netduinoplus2 -cpu cortex-m4 -singlestep -d exec,nochain`, one trace line per
executed instruction, counted between each function's entry and its return address): e.g. lm 75 738,
accumulate_sample 4 024 993 over the 26 300 calls. Unicorn is itself derived from QEMU, so this checks the
block counting here, not QEMU's decoder; the cycle table is the estimate.

Output: JSON on stdout. Needs: python3 -m pip install unicorn capstone pyelftools.
"""

import argparse
import bisect
import json
import re
import struct
import sys
import time

try:
    import capstone
    from capstone import arm_const as A
    from elftools.elf.elffile import ELFFile
    from elftools.elf.sections import SymbolTableSection
    from unicorn import (UC_ARCH_ARM, UC_ARCH_RISCV, UC_HOOK_BLOCK, UC_HOOK_INTR, UC_HOOK_MEM_WRITE,
                         UC_MODE_MCLASS, UC_MODE_RISCV32, UC_MODE_THUMB, Uc, UcError)
    from unicorn import arm_const as U
    from unicorn import riscv_const as R
except ImportError as e:  # pragma: no cover
    sys.exit(f"cyclecount.py: {e}: python3 -m pip install unicorn capstone pyelftools")

FLASH = (0x0800_0000, 512 * 1024)
RAM = (0x2000_0000, 128 * 1024)
# System control space (SCB, NVIC, SysTick, FPU registers): plain memory here.
PPB = (0xE000_0000, 0x10_0000)
# RISC-V (examples/riscv/link.x, QEMU virt): code and data from 0x80000000, RAM up to 0x800A0000; the
# SiFive test device (exit) and the 16550 UART (output) as write-hooked pages.
RV_MEMORY = (0x8000_0000, 640 * 1024)
RV_TEST_DEVICE = 0x10_0000
RV_UART = 0x1000_0000
RV_TEST_PASS = 0x5555
PAINT = 0xA5
# Semihosting operations (ARM "Semihosting for AArch32 and AArch64").
SYS_OPEN, SYS_WRITEC, SYS_WRITE0, SYS_WRITE, SYS_EXIT, SYS_EXIT_EXTENDED = 0x01, 0x03, 0x04, 0x05, 0x18, 0x20
ADP_STOPPED_APPLICATION_EXIT = 0x20026
EXCP_BKPT = 7

BRANCHES = {A.ARM_INS_B, A.ARM_INS_BL, A.ARM_INS_BLX, A.ARM_INS_BX, A.ARM_INS_CBZ, A.ARM_INS_CBNZ}
ONE_CYCLE_FP = {
    A.ARM_INS_VADD, A.ARM_INS_VSUB, A.ARM_INS_VMUL, A.ARM_INS_VNMUL, A.ARM_INS_VNEG, A.ARM_INS_VABS,
    A.ARM_INS_VCMP, A.ARM_INS_VCMPE, A.ARM_INS_VCVT, A.ARM_INS_VCVTR, A.ARM_INS_VCVTA, A.ARM_INS_VCVTM,
    A.ARM_INS_VCVTN, A.ARM_INS_VCVTP, A.ARM_INS_VMRS, A.ARM_INS_VMSR, A.ARM_INS_VSELEQ, A.ARM_INS_VSELGE,
    A.ARM_INS_VSELGT, A.ARM_INS_VSELVS, A.ARM_INS_VMAXNM, A.ARM_INS_VMINNM, A.ARM_INS_VRINTA,
    A.ARM_INS_VRINTM, A.ARM_INS_VRINTN, A.ARM_INS_VRINTP, A.ARM_INS_VRINTR, A.ARM_INS_VRINTX,
    A.ARM_INS_VRINTZ,
}
MAC_FP = {A.ARM_INS_VMLA, A.ARM_INS_VMLS, A.ARM_INS_VNMLA, A.ARM_INS_VNMLS, A.ARM_INS_VFMA, A.ARM_INS_VFMS,
          A.ARM_INS_VFNMA, A.ARM_INS_VFNMS}
SINGLE_LOADS_STORES = {
    A.ARM_INS_LDR, A.ARM_INS_LDRB, A.ARM_INS_LDRH, A.ARM_INS_LDRSB, A.ARM_INS_LDRSH, A.ARM_INS_LDRT,
    A.ARM_INS_LDRBT, A.ARM_INS_LDRHT, A.ARM_INS_LDRSBT, A.ARM_INS_LDRSHT, A.ARM_INS_LDREX,
    A.ARM_INS_STR, A.ARM_INS_STRB, A.ARM_INS_STRH, A.ARM_INS_STRT, A.ARM_INS_STRBT, A.ARM_INS_STRHT,
    A.ARM_INS_STREX,
}
# The only 32-bit instructions of ARMv6-M.
ARMV6M_WIDE = {A.ARM_INS_BL, A.ARM_INS_MSR, A.ARM_INS_MRS, A.ARM_INS_DMB, A.ARM_INS_DSB, A.ARM_INS_ISB}
MULTIPLE = {A.ARM_INS_LDM, A.ARM_INS_LDMDB, A.ARM_INS_STM, A.ARM_INS_STMDB, A.ARM_INS_PUSH, A.ARM_INS_POP}
FP_MULTIPLE = {A.ARM_INS_VLDMIA, A.ARM_INS_VLDMDB, A.ARM_INS_VSTMIA, A.ARM_INS_VSTMDB, A.ARM_INS_VPUSH,
               A.ARM_INS_VPOP}


class Insn:
    """One decoded instruction: its base cycles, and whether it may branch (adds P when taken)."""

    __slots__ = ("addr", "size", "name", "cycles", "branch", "single_ls")

    def __init__(self, addr, size, name, cycles, branch, single_ls):
        self.addr, self.size, self.name = addr, size, name
        self.cycles, self.branch, self.single_ls = cycles, branch, single_ls


def reg_words(cs_insn, first_operand):
    """32-bit words moved by a register-list instruction (D registers count 2)."""
    n = 0
    for op in cs_insn.operands[first_operand:]:
        if op.type == A.ARM_OP_REG:
            name = cs_insn.reg_name(op.reg) or ""
            n += 2 if name.startswith("d") else 1
    return n


def writes_pc(cs_insn):
    return any(op.type == A.ARM_OP_REG and op.reg == A.ARM_REG_PC and (op.access & capstone.CS_AC_WRITE)
               for op in cs_insn.operands)


def price(cs_insn):
    """(base cycles, may branch, is a single load/store) of one instruction, per the table above."""
    i = cs_insn.id
    if i in BRANCHES:
        return 1, True, False
    if i in (A.ARM_INS_TBB, A.ARM_INS_TBH):
        return 2, True, False
    if i in MULTIPLE:
        first = 0 if i in (A.ARM_INS_PUSH, A.ARM_INS_POP) else 1
        regs = sum(1 for op in cs_insn.operands[first:] if op.type == A.ARM_OP_REG)
        return 1 + regs, writes_pc(cs_insn), False
    if i in FP_MULTIPLE:
        first = 0 if i in (A.ARM_INS_VPUSH, A.ARM_INS_VPOP) else 1
        return 1 + reg_words(cs_insn, first), False, False
    if i in (A.ARM_INS_LDRD, A.ARM_INS_STRD):
        return 3, False, False
    if i in SINGLE_LOADS_STORES:
        return 2, writes_pc(cs_insn), True
    if i in (A.ARM_INS_VLDR, A.ARM_INS_VSTR):
        return 2, False, False
    if i in (A.ARM_INS_SDIV, A.ARM_INS_UDIV):
        return 7, False, False
    if i in (A.ARM_INS_MLA, A.ARM_INS_MLS):
        return 2, False, False
    if i in (A.ARM_INS_VDIV, A.ARM_INS_VSQRT):
        return 14, False, False
    if i in MAC_FP:
        return 3, False, False
    if i == A.ARM_INS_VMOV:
        # Two core registers to/from a D register or two S registers: 2; otherwise 1.
        regs = sum(1 for op in cs_insn.operands if op.type == A.ARM_OP_REG)
        return (2 if regs >= 3 else 1), False, False
    if i in ONE_CYCLE_FP:
        return 1, False, False
    # Data processing, multiplies (MUL, SMULL, UMULL, SMLAL, UMLAL), extends, bit fields, IT, NOP, MOV to
    # PC is a branch.
    return 1, writes_pc(cs_insn), False


def price_m0plus(cs_insn):
    """(base cycles, may branch, is a pipelined single load/store) on the Cortex-M0+ (table above)."""
    i = cs_insn.id
    if i == A.ARM_INS_BL:
        return 2, True, False
    if i in BRANCHES:
        return 1, True, False
    if i in MULTIPLE:
        first = 0 if i in (A.ARM_INS_PUSH, A.ARM_INS_POP) else 1
        regs = sum(1 for op in cs_insn.operands[first:] if op.type == A.ARM_OP_REG)
        pc = writes_pc(cs_insn)
        return 1 + regs + (1 if pc else 0), pc, False
    if i in SINGLE_LOADS_STORES:
        return 2, writes_pc(cs_insn), False
    return 1, writes_pc(cs_insn), False


RV_LOADS = {"lb", "lh", "lw", "lbu", "lhu", "c.lw", "c.lwsp"}
RV_STORES = {"sb", "sh", "sw", "c.sw", "c.swsp"}
RV_DIVIDES = {"div", "divu", "rem", "remu"}
RV_JUMPS = {"jal", "jalr", "j", "jr", "ret", "c.j", "c.jal", "c.jr", "c.jalr"}


def rv_is_branch(name):
    return name in RV_JUMPS or name.startswith("b") or name.startswith("c.b")


def price_rv(cs_insn):
    """(base cycles, may branch, is a pipelined single load/store) in the RV32IMC model (table above)."""
    name = cs_insn.mnemonic
    if rv_is_branch(name):
        return 1, True, False
    if name in RV_LOADS:
        return 2, False, False
    if name in RV_DIVIDES:
        return 34, False, False
    return 1, False, False


class Cpu:
    """One emulated core: Unicorn and Capstone modes, registers, memory and timing table."""

    def __init__(self, name, cost_model, penalty, price, riscv=False, armv6m=False):
        self.name, self.cost_model, self.penalty, self.price = name, cost_model, penalty, price
        self.riscv = riscv
        self.armv6m = armv6m
        if riscv:
            self.uc_mode = (UC_ARCH_RISCV, UC_MODE_RISCV32)
            self.cs_mode = (capstone.CS_ARCH_RISCV, capstone.CS_MODE_RISCV32 | capstone.CS_MODE_RISCVC)
            self.sp, self.ra, self.pc = R.UC_RISCV_REG_SP, R.UC_RISCV_REG_RA, R.UC_RISCV_REG_PC
            self.memory = (RV_MEMORY,)
        else:
            self.uc_mode = (UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
            self.cs_mode = (capstone.CS_ARCH_ARM, capstone.CS_MODE_THUMB | capstone.CS_MODE_MCLASS)
            self.sp, self.ra, self.pc = U.UC_ARM_REG_SP, U.UC_ARM_REG_LR, U.UC_ARM_REG_PC
            self.memory = (FLASH, RAM, PPB)

    def capstone(self):
        cs = capstone.Cs(*self.cs_mode)
        cs.detail = True
        return cs


CPUS = {
    "cortex-m4": Cpu("cortex-m4", "unicorn + Cortex-M4 timing table (+-10-30 % vs silicon); taken branch +{p} cycle",
                     1, price),
    "cortex-m0plus": Cpu("cortex-m0plus", "unicorn (every instruction checked ARMv6-M) + Cortex-M0+ TRM timing table (load/store 2, "
                         "taken branch 2, BL 3, single-cycle multiplier assumed; soft float); taken branch +{p} cycle", 1,
                         price_m0plus, armv6m=True),
    "rv32imc": Cpu("rv32imc", "unicorn RV32 + a simple model, not a chip (ALU and mul 1, load 2, store 1, taken "
                   "branch and jump 1+{p}, div/rem 34)", 2, price_rv, riscv=True),
}


class Image:
    def __init__(self, path):
        self.path = path
        with open(path, "rb") as f:
            self.raw = f.read()
        with open(path, "rb") as f:
            elf = ELFFile(f)
            self.entry = elf["e_entry"]
            self.segments = [(s["p_paddr"], s.data()) for s in elf.iter_segments()
                             if s["p_type"] == "PT_LOAD" and s["p_filesz"]]
            self.symbols = {}
            self.functions = []  # (start, size, name)
            for sec in elf.iter_sections():
                if isinstance(sec, SymbolTableSection):
                    for sym in sec.iter_symbols():
                        if sym.name:
                            self.symbols.setdefault(sym.name, sym["st_value"])
                        if sym["st_info"]["type"] == "STT_FUNC" and sym["st_size"]:
                            self.functions.append((sym["st_value"] & ~1, sym["st_size"], sym.name))
            self.text = {}
            for sec in elf.iter_sections():
                if sec["sh_flags"] & 0x4 and sec["sh_type"] == "SHT_PROGBITS":  # SHF_EXECINSTR
                    self.text[sec["sh_addr"]] = sec.data()
        self.functions.sort()

    def symbol(self, name):
        if name not in self.symbols:
            sys.exit(f"cyclecount.py: symbol {name} not in {self.path}")
        return self.symbols[name] & ~1

    def code(self, addr, size):
        for base, data in self.text.items():
            if base <= addr and addr + size <= base + len(data):
                return data[addr - base:addr - base + size]
        return b""


class Measurement:
    def __init__(self):
        self.calls = 0
        self.entry_sp = 0
        self.instructions = []
        self.cycles = []
        self.stack = []


class Emulator:
    """Runs the image from reset to its semihosting exit; one block hook counts the measured calls."""

    def __init__(self, image, cpu, functions, branch_penalty, timeout_s, profile=False):
        self.image = image
        self.cpu = cpu
        self.profile = profile
        self.by_block = {}  # (measured function, block address) -> [executions, cycles, lowest sp]
        self.penalty = branch_penalty
        self.deadline = time.monotonic() + timeout_s
        self.cs = cpu.capstone()
        self.uc = Uc(*cpu.uc_mode)
        for base, size in cpu.memory:
            self.uc.mem_map(base, size)
        if cpu.riscv:
            for page in (RV_TEST_DEVICE, RV_UART):
                self.uc.mem_map(page, 0x1000)
            self.uc.hook_add(UC_HOOK_MEM_WRITE, self._on_device_write, begin=RV_TEST_DEVICE, end=RV_TEST_DEVICE + 3)
            self.uc.hook_add(UC_HOOK_MEM_WRITE, self._on_device_write, begin=RV_UART, end=RV_UART)
        for addr, data in image.segments:
            self.uc.mem_write(addr, data)
        self.entries = {image.symbol(f): f for f in functions}
        self.results = {f: Measurement() for f in functions}
        self.stdout = []
        self.exit_ok = None
        self.blocks = {}
        # Painting starts above the statics (cortex-m-rt's __sheap, or __ebss).
        self.paint_floor = image.symbols.get("__sheap", image.symbols.get("__ebss", RAM[0]))
        self.stop_reason = None
        self.current = None  # (name, entry sp, return address) of the call being measured
        self.uc.hook_add(UC_HOOK_INTR, self._on_interrupt)
        # Installed once for the whole run: hooks added later would miss already translated blocks.
        self.uc.hook_add(UC_HOOK_BLOCK, self._on_block)

    def _on_interrupt(self, uc, intno, _):
        self.stop_reason = ("interrupt", intno)
        uc.emu_stop()

    def _on_device_write(self, uc, _access, addr, _size, value, _):
        """RISC-V: a byte to the UART is output; a word to the test device ends the run."""
        if addr == RV_UART:
            self.stdout.append(chr(value & 0xFF))
        else:
            self.exit_ok = value == RV_TEST_PASS
            self.stop_reason = ("exit", value)
            uc.emu_stop()

    def _decode(self, addr, size):
        insns = list(self.cs.disasm(bytes(self.uc.mem_read(addr, size)), addr))
        if self.cpu.armv6m:
            for ins in insns:
                if ins.size == 4 and ins.id not in ARMV6M_WIDE:
                    sys.exit(f"cyclecount.py: {ins.mnemonic} {ins.op_str} at {ins.address:#x} ({self._where(addr)}) "
                             "is not an ARMv6-M instruction")
        return [Insn(ins.address, ins.size, ins.insn_name(), *self.cpu.price(ins)) for ins in insns]

    def _price_block(self, addr, size):
        insns = self._decode(addr, size)
        cycles = 0
        prev_ls = False
        for ins in insns:
            # A single load/store right after another one pipelines: 1 cycle instead of 2.
            cycles += 1 if (ins.single_ls and prev_ls) else ins.cycles
            prev_ls = ins.single_ls
        last = insns[-1] if insns else None
        return len(insns), cycles, (last.addr + last.size) if last and last.branch else None

    def _on_block(self, uc, addr, size, _):
        if self.current is None:
            name = self.entries.get(addr)
            if name is None:
                return
            self._begin(name)
        elif addr == self.current[2]:
            self._end()
            return
        # The previous block ended in a branch, and this block does not follow it: the branch was taken.
        if self.last_branch_end is not None and addr != self.last_branch_end:
            self.cyc += self.penalty
        block = self.blocks.get((addr, size))
        if block is None:
            block = self.blocks[(addr, size)] = self._price_block(addr, size)
        n, cycles, self.last_branch_end = block
        self.ins += n
        self.cyc += cycles
        if self.profile:
            key = (self.current[0], addr)
            entry = self.by_block.setdefault(key, [0, 0, 0, 0xFFFF_FFFF])
            entry[0] += 1
            entry[1] += n
            entry[2] += cycles
            entry[3] = min(entry[3], uc.reg_read(self.cpu.sp))

    def _begin(self, name):
        uc = self.uc
        sp = uc.reg_read(self.cpu.sp)
        ret = uc.reg_read(self.cpu.ra) & ~1
        uc.mem_write(self.paint_floor, bytes([PAINT]) * (sp - self.paint_floor))
        self.current = (name, sp, ret)
        self.ins = self.cyc = 0
        self.last_branch_end = None

    def _end(self):
        name, sp, _ = self.current
        self.current = None
        # The return itself is a taken branch.
        if self.last_branch_end is not None:
            self.cyc += self.penalty
        floor = self.paint_floor
        painted = bytes(self.uc.mem_read(floor, sp - floor))
        untouched = len(painted) - len(painted.lstrip(bytes([PAINT])))
        m = self.results[name]
        m.entry_sp = sp
        m.calls += 1
        m.instructions.append(self.ins)
        m.cycles.append(self.cyc)
        m.stack.append(sp - floor - untouched)

    def _where(self, pc):
        for start, size, name in self.image.functions:
            if start <= pc < start + size:
                return name
        return "?"

    def _read_words(self, addr, n):
        return struct.unpack(f"<{n}I", self.uc.mem_read(addr, 4 * n))

    def _semihosting(self):
        """Serves the semihosting call at a `BKPT 0xAB`; `True` at the program's exit."""
        op, arg = self.uc.reg_read(U.UC_ARM_REG_R0), self.uc.reg_read(U.UC_ARM_REG_R1)
        result = 0
        if op == SYS_OPEN:
            result = 1
        elif op == SYS_WRITE:
            _, ptr, length = self._read_words(arg, 3)
            self.stdout.append(bytes(self.uc.mem_read(ptr, length)).decode("utf-8", "replace"))
        elif op == SYS_WRITEC:
            self.stdout.append(chr(self.uc.mem_read(arg, 1)[0]))
        elif op == SYS_WRITE0:
            data = bytearray()
            while (b := self.uc.mem_read(arg + len(data), 1)[0]) != 0:
                data.append(b)
            self.stdout.append(data.decode("utf-8", "replace"))
        elif op == SYS_EXIT:
            self.exit_ok = arg == ADP_STOPPED_APPLICATION_EXIT
            return True
        elif op == SYS_EXIT_EXTENDED:
            reason, code = self._read_words(arg, 2)
            self.exit_ok = reason == ADP_STOPPED_APPLICATION_EXIT and code == 0
            return True
        else:
            result = 0xFFFF_FFFF
        self.uc.reg_write(U.UC_ARM_REG_R0, result)
        return False

    def run(self):
        if self.cpu.riscv:
            return self._run_riscv()
        sp, reset = self._read_words(FLASH[0], 2)
        self.uc.reg_write(U.UC_ARM_REG_SP, sp)
        pc = reset & ~1
        while True:
            remaining = self.deadline - time.monotonic()
            if remaining <= 0:
                sys.exit("cyclecount.py: time limit reached")
            self.stop_reason = None
            try:
                self.uc.emu_start(pc | 1, 0, timeout=int(remaining * 1e6))
            except UcError as e:
                pc = self.uc.reg_read(U.UC_ARM_REG_PC)
                sys.exit(f"cyclecount.py: emulation error at {pc:#x} ({self._where(pc)}): {e}")
            pc = self.uc.reg_read(U.UC_ARM_REG_PC)
            if self.stop_reason == ("interrupt", EXCP_BKPT) and self.image.code(pc, 2) == b"\xab\xbe":
                if self._semihosting():
                    return
                pc += 2
            elif self.stop_reason is None:
                sys.exit(f"cyclecount.py: stopped at {pc:#x} ({self._where(pc)}) without exiting (time limit?)")
            else:
                sys.exit(f"cyclecount.py: exception {self.stop_reason[1]} at {pc:#x} ({self._where(pc)})")


    def _run_riscv(self):
        """From the ELF entry to the test device's exit (the image sets its own stack pointer)."""
        remaining = self.deadline - time.monotonic()
        try:
            self.uc.emu_start(self.image.entry, 0, timeout=int(remaining * 1e6))
        except UcError as e:
            pc = self.uc.reg_read(R.UC_RISCV_REG_PC)
            sys.exit(f"cyclecount.py: emulation error at {pc:#x} ({self._where(pc)}): {e}")
        pc = self.uc.reg_read(R.UC_RISCV_REG_PC)
        if self.stop_reason is None:
            sys.exit(f"cyclecount.py: stopped at {pc:#x} ({self._where(pc)}) without exiting (time limit?)")
        if self.stop_reason[0] != "exit":
            sys.exit(f"cyclecount.py: exception {self.stop_reason[1]} at {pc:#x} ({self._where(pc)})")


def profile(emu):
    """Per measured function: the symbols its calls executed, by cycles, with the stack depth (bytes below
    the measured call's entry stack pointer) reached in each (block-start granularity)."""
    entry_sp = {}
    for name, m in emu.results.items():
        entry_sp[name] = m.entry_sp
    out = {}
    for (fn, addr), (count, ins, cyc, low_sp) in emu.by_block.items():
        sym = emu._where(addr)
        row = out.setdefault(fn, {}).setdefault(sym, {"instructions": 0, "cycles": 0, "stack_depth": 0})
        row["instructions"] += ins
        row["cycles"] += cyc
        row["stack_depth"] = max(row["stack_depth"], entry_sp[fn] - low_sp)
    return {fn: dict(sorted(rows.items(), key=lambda kv: -kv[1]["cycles"])) for fn, rows in out.items()}


PC_RELATIVE_LOADS = {A.ARM_INS_LDR: 4, A.ARM_INS_VLDR: 4, A.ARM_INS_LDRD: 8}


def literal_words(insns):
    """Addresses of the literal-pool words that PC-relative loads read (`ldr rX, [pc, #imm]`, `vldr`,
    `ldrd`): data in the code stream, not instructions."""
    words = set()
    for ins in insns:
        size = PC_RELATIVE_LOADS.get(ins.id)
        if size is None:
            continue
        for op in ins.operands:
            if op.type == A.ARM_OP_MEM and op.mem.base == A.ARM_REG_PC:
                target = ((ins.address + 4) & ~3) + op.mem.disp
                if ins.id == A.ARM_INS_VLDR and ins.op_str.startswith("d"):
                    size = 8
                words.update(range(target, target + size, 2))
    return words


def code_instructions(cs, code, base):
    """The instructions of one function, without its literal pools. A plain linear decode reads a float
    constant as an instruction (a 32-bit literal can decode as a branch into core::fmt, which then
    counted as linked code); here the halfwords that PC-relative loads read are skipped, and an
    undecodable halfword is stepped over instead of ending the decode."""
    def decode(skip):
        out, at = [], 0
        while at < len(code):
            if base + at in skip:
                at += 2
                continue
            ins = next(cs.disasm(code[at:at + 4], base + at, 1), None)
            if ins is None:
                at += 2
                continue
            out.append(ins)
            at += ins.size
        return out

    # Two passes: the first finds the pools (its loads are real: pools follow the code that uses them).
    return decode(literal_words(decode(set())))


def arm_targets(cs, code, base):
    """Direct branch and call targets (B/BL/CBZ/CBNZ) of one Thumb function."""
    for ins in code_instructions(cs, code, base):
        if ins.id in (A.ARM_INS_B, A.ARM_INS_BL, A.ARM_INS_CBZ, A.ARM_INS_CBNZ):
            ops = [op for op in ins.operands if op.type == A.ARM_OP_IMM]
            if ops:
                yield ops[-1].imm


def rv_targets(cs, code, base):
    """Direct jump, branch and call targets of one RISC-V function: JAL/J/branches (PC-relative immediates)
    and the AUIPC + JALR pairs of unrelaxed calls and tail calls."""
    upper = {}  # register -> address an AUIPC put in it
    for ins in cs.disasm(code, base):
        ops = ins.operands
        regs = [op.reg for op in ops if op.type == capstone.riscv.RISCV_OP_REG]
        imms = [op.imm for op in ops if op.type == capstone.riscv.RISCV_OP_IMM]
        if ins.mnemonic == "auipc" and regs and imms:
            hi = imms[0] - (1 << 20) if imms[0] >= 1 << 19 else imms[0]
            upper[regs[0]] = ins.address + (hi << 12)
            continue
        if ins.mnemonic == "jalr" and len(regs) >= 2 and regs[1] in upper and imms:
            yield upper[regs[1]] + imms[-1]
        elif rv_is_branch(ins.mnemonic) and ins.mnemonic not in ("jalr", "jr", "ret", "c.jr", "c.jalr") and imms:
            yield ins.address + imms[-1]
        if regs:
            upper.pop(regs[0], None)


def static_code(image, roots, cpu):
    """Code bytes reachable from `roots` through direct calls and tail calls, by crate.

    The walk stops at core's panic entry points: the panic handler belongs to the application."""
    by_start = {start: (size, name) for start, size, name in image.functions}
    starts = sorted(by_start)
    cs = cpu.capstone()
    targets = rv_targets if cpu.riscv else arm_targets

    def containing(addr):
        k = bisect.bisect_right(starts, addr) - 1
        if k >= 0 and addr < starts[k] + by_start[starts[k]][0]:
            return starts[k]
        return None

    seen, todo = set(), [image.symbol(r) for r in roots]
    while todo:
        f = todo.pop()
        if f in seen or f not in by_start:
            continue
        seen.add(f)
        size, name = by_start[f]
        if "panicking" in name:
            continue
        for addr in targets(cs, image.code(f, size), f):
            target = containing(addr)
            if target is not None and target != f:
                todo.append(target)
    crates = {}
    functions = []
    for f in sorted(seen):
        size, name = by_start[f]
        crate = crate_of(name)
        crates[crate] = crates.get(crate, 0) + size
        functions.append({"name": name, "size": size, "crate": crate})
    functions.sort(key=lambda fn: -fn["size"])
    return {"roots": roots, "bytes": sum(crates.values()), "by_crate": crates, "functions": functions}


def crate_of(symbol):
    """The crate of a mangled Rust symbol (legacy `_ZN<len><crate>` or v0 `_R...C<hash>_<len><crate>`);
    the unmangled entry points are the bench's, `__aeabi_*`/`mem*` are compiler builtins, C math names libm."""
    m = re.match(r"_ZN(\d+)", symbol)
    if m:
        k = m.end()
        return symbol[k:k + int(m.group(1))]
    m = re.match(r"_R\w*?C(?:s[0-9A-Za-z]*_)?(\d+)", symbol)
    if m:
        k = m.end()
        return symbol[k:k + int(m.group(1))]
    if symbol.startswith("__") or symbol.startswith("mem"):
        return "compiler_builtins"
    if re.fullmatch(r"(f(max|min)|sqrt|tan|sin|cos|round|fabs)f?", symbol):
        return "libm"
    return "bench"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("elf", help="the bench firmware ELF")
    ap.add_argument("--cpu", choices=sorted(CPUS), default="cortex-m4", help="core and timing table")
    ap.add_argument("--functions", default="accumulate_fifo,accumulate_sample,apply_sample,taga_generation,full_calibration,lm,initial_estimate")
    ap.add_argument("--branch-penalty", type=int, default=None,
                    help="extra cycles of a taken branch (P; default 1 on ARM, 2 on RISC-V)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds")
    ap.add_argument("--profile", action="store_true",
                    help="also attribute instructions, cycles and stack depth to the symbols executed")
    args = ap.parse_args()
    functions = [f for f in args.functions.split(",") if f]
    image = Image(args.elf)
    cpu = CPUS[args.cpu]
    penalty = cpu.penalty if args.branch_penalty is None else args.branch_penalty
    emu = Emulator(image, cpu, functions, penalty, args.timeout, args.profile)
    started = time.monotonic()
    emu.run()
    out = {
        "elf": args.elf,
        "exit_ok": emu.exit_ok,
        "stdout": "".join(emu.stdout),
        "cpu": cpu.name,
        "branch_penalty": penalty,
        "cost_model": cpu.cost_model.format(p=penalty),
        "functions": {},
        # What a firmware links for the calibration path: accumulate, calibrate, apply. (taga_generation and
        # lm are benchmark-only copies of code that full_calibration contains.)
        "static_code": static_code(image, ["accumulate_sample", "full_calibration", "apply_sample"], cpu),
        "seconds": round(time.monotonic() - started, 2),
    }
    for name, m in emu.results.items():
        if m.calls == 0:
            sys.exit(f"cyclecount.py: {name} was never called")
        out["functions"][name] = {
            "calls": m.calls,
            "instructions": {"total": sum(m.instructions), "mean": sum(m.instructions) / m.calls,
                             "min": min(m.instructions), "max": max(m.instructions)},
            "cycles": {"total": sum(m.cycles), "mean": sum(m.cycles) / m.calls,
                       "min": min(m.cycles), "max": max(m.cycles)},
            "peak_stack_bytes": max(m.stack),
        }
    if args.profile:
        out["profile"] = profile(emu)
    json.dump(out, sys.stdout, indent=1)
    print()
    return 0 if emu.exit_ok else 1


if __name__ == "__main__":
    sys.exit(main())
