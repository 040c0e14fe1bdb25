#!/usr/bin/env bash
# Calibrates every multi-pose real set in ../shared/data/real with one command line each and prints the
# README's Markdown table. Usage: bash tools/real_data_table.sh [path/to/accelcal]
set -uo pipefail
cd "$(dirname "$0")/.."
BIN="${1:-target/release/accelcal}"
D=../shared/data/real
[ -d "$D" ] || { echo "no $D: the real recordings are not beside the project" >&2; exit 1; }
sets=(
  "imu_tk_xsens_mti/xsens_acc.csv|"
  "hassan_lis3dh_30pos/MobileAccData30orientationRawSample01.csv|"
  "hassan_lis3dh_30pos/author_interval_means.csv|--means"
  "hassan_lis3dh_30pos/CalibrationOfLowCostTriaxialInertialSensors50.csv|--means"
  "fastahrs_fxos8700/data_sample.clean.csv|"
  "fastahrs_fxos8700/data_sample2.clean.csv|"
  "ck_explorer_acc_sphere/acc_log.csv|"
  "ck_explorer_acc_sphere/derived_block_means.csv|--means"
  "michaelwro_178pos/acceldata-example.csv|--means"
  "imutk_windows_20pos/imu.csv|"
  "tomisuarez_mpu6050_10pos/example_data_calibration.plain.csv|"
  "tomisuarez_mpu6050_10pos/derived_static_intervals.csv|--means"
  "avrlabs_mpu6050/derived_notebook_26pos_means.csv|--means"
)
echo "| set (file) | options | units | poses | RMSE before (mg) | after | leave-one-out | noise floor | verdict | held at nominal / poses left out |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for s in "${sets[@]}"; do
  file="${s%%|*}"; opts="${s#*|}"
  # shellcheck disable=SC2086
  out=$("$BIN" calibrate "$D/$file" $opts --json 2>/tmp/real_data_table.err)
  code=$?
  if [ -z "$out" ]; then
    echo "| \`$file\` | \`${opts:-(none)}\` | | | | | | | | exit $code: $(head -c 160 /tmp/real_data_table.err | tr '\n|' '  ' | sed "s#$D/##") |"
    continue
  fi
  python3 - "$file" "${opts:-(none)}" "$code" "$out" <<'PY'
import json, sys
file, opts, code, out = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
def f(v):
    return "?" if v is None else f"{v:.3g}"
r = out["rmse_mg"]
v = out["verdict"]
reasons = [k.replace("_", " ") for k in ["rmse_over_limit", "model_misfit", "implausible", "not_converged"] if v.get(k)]
if v["undetermined"]:
    reasons.append("poorly determined " + " ".join(v["undetermined"]))
verdict = "pass" if v["pass"] else "fail: " + "; ".join(reasons)
held = " ".join(v.get("held_at_nominal", [])) or "-"
left = " ".join(f"#{i + 1}" for i in v.get("poses_left_out", [])) or "-"
print(f"| `{file}` | `{opts}` | {out['units']} | {len(out['poses'])} | {f(r['before'])} | {f(r['after'])} | {f(r['loo'])} | {f(out['noise_floor_mg'])} | {verdict} | {held} / {left} |")
PY
done
