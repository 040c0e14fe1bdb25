#!/usr/bin/env bash
# Runs the simulated calibration on an emulated Cortex-M4F and checks it against the host.
#
# 1. builds examples/qemu_calibrate.rs in release for thumbv7em-none-eabihf;
# 2. runs it in QEMU (netduinoplus2, STM32F405) with a time limit; its report comes over semihosting
#    and its exit code is the firmware's verdict (0 only if the calibration passed and every parameter
#    is within tolerance of the truth);
# 3. runs the same generator and pipeline on the host (tests/qemu_parity.rs);
# 4. fails unless both reports are identical line for line (same seeds -> same bits).
#
# Needs: qemu-system-arm (Debian: apt-get install -y qemu-system-arm), rustup target thumbv7em-none-eabihf.
# Outputs go to $CARGO_TARGET_DIR/qemu/ (default target/qemu/). QEMU_TIMEOUT (seconds) defaults to 120.
set -euo pipefail

cd "$(dirname "$0")/.."
TARGET=thumbv7em-none-eabihf
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
mkdir -p "$CARGO_TARGET_DIR"
CARGO_TARGET_DIR="$(cd "$CARGO_TARGET_DIR" && pwd)"
OUT="$CARGO_TARGET_DIR/qemu"
mkdir -p "$OUT"
TIMEOUT="${QEMU_TIMEOUT:-120}"

if ! command -v qemu-system-arm >/dev/null; then
    echo "qemu.sh: qemu-system-arm not found (apt-get install -y qemu-system-arm)" >&2
    exit 1
fi
if command -v rustup >/dev/null && ! rustup target list --installed | grep -qx "$TARGET"; then
    rustup target add "$TARGET"
fi

echo "== build examples/qemu_calibrate ($TARGET, release)"
cargo build -p accelcal --release --target "$TARGET" --example qemu_calibrate
ELF="$CARGO_TARGET_DIR/$TARGET/release/examples/qemu_calibrate"
if command -v llvm-size >/dev/null; then
    llvm-size "$ELF"
fi

echo "== run in $(qemu-system-arm --version | head -n 1), limit ${TIMEOUT}s"
set +e
timeout "$TIMEOUT" qemu-system-arm -M netduinoplus2 -cpu cortex-m4 -nographic \
    -semihosting-config enable=on,target=native -kernel "$ELF" \
    </dev/null >"$OUT/qemu.txt" 2>"$OUT/qemu.stderr"
status=$?
set -e
cat "$OUT/qemu.txt"
if [ -s "$OUT/qemu.stderr" ]; then
    echo "-- qemu stderr:"
    cat "$OUT/qemu.stderr"
fi
if [ "$status" -eq 124 ]; then
    echo "qemu.sh: QEMU did not exit within ${TIMEOUT}s" >&2
    exit 1
fi
if [ "$status" -ne 0 ]; then
    echo "qemu.sh: the firmware reported failure (QEMU exit status $status)" >&2
    exit 1
fi

echo "== the same run on the host (tests/qemu_parity.rs)"
QEMU_PARITY_OUT="$OUT/host.txt" cargo test -p accelcal --test qemu_parity

# The report lines (QEMU adds nothing to stdout today; filter anyway so a notice cannot break the check).
report='^(run|poses|pose|method|param|verdict|blob|result|error|guided)\b'
grep -E "$report" "$OUT/qemu.txt" >"$OUT/qemu.report" || true
grep -E "$report" "$OUT/host.txt" >"$OUT/host.report" || true
if [ "$(grep -c '^param ' "$OUT/qemu.report")" -ne 9 ]; then
    echo "qemu.sh: QEMU printed $(grep -c '^param ' "$OUT/qemu.report") parameter lines, expected 9" >&2
    exit 1
fi
if ! diff -u "$OUT/host.report" "$OUT/qemu.report"; then
    echo "qemu.sh: the QEMU report differs from the host's (above: - host, + QEMU)" >&2
    exit 1
fi
echo "qemu.sh: QEMU and host reports are identical ($(wc -l <"$OUT/qemu.report") lines); firmware verdict PASS"

echo "== the guided session in an Embassy task (feature async) on the emulated Cortex-M4F"
cargo build -p accelcal --release --target "$TARGET" --features async --example embassy_session
timeout "$TIMEOUT" qemu-system-arm -M netduinoplus2 -cpu cortex-m4 -nographic \
    -semihosting-config enable=on,target=native -kernel "$CARGO_TARGET_DIR/$TARGET/release/examples/embassy_session" \
    </dev/null | tee "$OUT/embassy.txt"
grep -q "verdict pass true" "$OUT/embassy.txt"
echo "qemu.sh: the Embassy session passed its verdict"
