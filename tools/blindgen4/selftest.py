#!/usr/bin/env python3
"""Physics self-test of generate.py.

    python3 selftest.py [--dir DIR] [--per-family N] [--seed S]

Generates a set (default target/bg4/selftest-set, seed 7, 4 per family) unless DIR already has a
manifest, then checks every log:
  * format: header, row count, monotonic timestamps, counts within full scale, >= 12 holds;
  * pose means vs the truth affine model: r_i = m_i - (A g_i + b) (g_i the true gravity direction
    of pose i in the sensor frame, A and b the true affine map, all from the manifest's `truth`);
  * clean logs: rms(r) and the corrected norms |A^-1 (m_i - b)| - 1 are within a few visibility floors;
  * drift/temperature offset shapes: peak-to-peak of r over time ~ the manifest magnitude;
  * scale-nonlinearity: r matches the k2 a^2 + k3 a^3 prediction from the manifest params;
  * colored-noise: std over holds of r ~ magnitude; offset-step: the step in r ~ the step vector;
  * temperature column: present where required, on its LSB grid.
"""

import argparse
import json
import os
import subprocess
import sys

import numpy as np

G0 = 9.80665
HERE = os.path.dirname(os.path.abspath(__file__))


def load(d, e):
    path = os.path.join(d, e["file"])
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return header, data


def to_g(header, data, e):
    acc = data[:, 1:4].copy()
    if header[1] == "ax":
        acc *= e["truth"]["lsb_g"]
    elif "(m/s^2)" in header[1]:
        acc /= G0
    return acc


def pose_means(acc, e, lo=0.35, hi=0.95):
    odr = e["odr_hz"]
    ms = []
    tm = []
    for a, b in e["truth"]["holds"]:
        i0 = int(round((a + lo * (b - a)) * odr))
        i1 = int(round((a + hi * (b - a)) * odr))
        ms.append(acc[i0:i1].mean(axis=0))
        tm.append(0.5 * (a + b))
    return np.array(ms), np.array(tm)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", default=os.path.join(HERE, "..", "..", "target", "bg4", "selftest-set"))
    ap.add_argument("--per-family", type=int, default=4)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    if not os.path.exists(os.path.join(a.dir, "manifest.json")):
        subprocess.run([sys.executable, os.path.join(HERE, "generate.py"), "--out", a.dir,
                        "--per-family", str(a.per_family), "--seed", str(a.seed)], check=True)
    man = json.load(open(os.path.join(a.dir, "manifest.json")))
    fails = 0
    checks = 0

    def check(ok, e, what):
        nonlocal fails, checks
        checks += 1
        if not ok:
            fails += 1
        print(f"{'ok  ' if ok else 'FAIL'} {e['file']:<48} {what}")

    for e in man:
        header, data = load(a.dir, e)
        tr = e["truth"]
        A = np.array(tr["A"])
        b = np.array(tr["bias_g"])
        g = np.array(tr["pose_gravity_sensor"])
        fl = e["visibility_floor_mg"] * 1e-3
        # ---- format
        t = data[:, 0]
        half = 2 ** (e["part"]["bits"] - 1)
        fmt_ok = (len(data) == e["rows"] and np.all(np.diff(t) >= 0) and header[0] == "t"
                  and len(tr["holds"]) >= 12)
        if header[1] == "ax":
            fmt_ok &= bool(np.all(np.abs(data[:, 1:4]) <= half) and np.all(data[:, 1:4] == np.round(data[:, 1:4])))
        check(fmt_ok, e, f"format ({','.join(header)}; {e['rows']} rows, {len(tr['holds'])} holds)")
        acc = to_g(header, data, e)
        m, tm = pose_means(acc, e)
        r = m - (g @ A.T + b)
        fam, shape = e["family"], e["shape"]
        # ---- temperature column
        if fam == "temperature" or shape == "warmup-zero-tc":
            ok = header[-1] == "temp"
            if ok:
                lsbT = e["timing"]["thermometer"]["lsb_C"]
                q = data[:, -1] / lsbT
                ok = bool(np.all(np.abs(q - np.round(q)) < 1e-6))
                span = data[:, -1].max() - data[:, -1].min()
            check(ok, e, f"temperature column present, on its LSB grid, span {span:.2f} C")
        # ---- per family physics
        if fam == "clean":
            rms = np.sqrt((r ** 2).mean())
            cn = np.linalg.norm(np.linalg.solve(A, (m - b).T).T, axis=1) - 1
            tol = 4 * fl + 2e-5
            check(rms < tol and np.abs(cn).max() < 3 * tol, e,
                  f"clean: rms(r)={rms*1e3:.4f} mg, max|norm-1|={np.abs(cn).max()*1e3:.4f} mg, floor={fl*1e3:.4f} mg")
            # within-hold scatter equals the white noise through the anti-alias filter (fine-LSB parts)
            if e["part"]["lsb_mg"] < 0.5 * e["noise_sigma_mg"]:
                odr = e["odr_hz"]
                sds = []
                for (a_, b_) in tr["holds"]:
                    seg = acc[int(round((a_ + 0.3 * (b_ - a_)) * odr)):int(round(b_ * odr))]
                    sds.append(np.median(seg.std(axis=0)))
                ratio = np.median(sds) / (e["noise_sigma_mg"] * 1e-3)
                check(0.75 < ratio < 1.25, e, f"clean: within-hold std / predicted noise sigma = {ratio:.3f}")
        elif fam in ("drift", "temperature") and e["params"].get("target", "bias") == "bias" \
                and e["params"].get("law") != "scale":
            pp = (r.max(0) - r.min(0)).max()
            mag = e["magnitude"] * 1e-3
            # the pose means sample the curve at the holds only (a bit less than the full p-p) + noise
            ok = (0.5 * mag - 4 * fl) <= pp <= (1.1 * mag + 6 * fl)
            check(ok, e, f"{fam}: p-p of pose residuals {pp*1e3:.4f} mg vs magnitude {mag*1e3:.4f} mg (floor {fl*1e3:.4f})")
        elif fam == "scale-nonlinearity":
            p = e["params"]
            if "k2_mg_per_g2" in p:
                k2 = np.array(p["k2_mg_per_g2"]) * 1e-3
                k3 = np.array(p["k3_mg_per_g3"]) * 1e-3
                pred = k2 * g ** 2 + k3 * g ** 3
            else:
                k3 = np.array(p["k3_mg"]) * 1e-3
                k5 = p["k5_mg"] * 1e-3
                pred = k3 * g ** 3 - k5 * g * np.abs(g) ** 4
            pred = pred @ A.T
            res = r - pred
            ratio = np.sqrt((res ** 2).mean()) / max(np.sqrt((pred ** 2).mean()), 1e-12)
            ok = np.sqrt((res ** 2).mean()) < 4 * fl + 0.15 * np.sqrt((pred ** 2).mean())
            check(ok, e, f"nonlinearity: rms(pred) {np.sqrt((pred**2).mean())*1e3:.4f} mg, rms(r-pred) "
                         f"{np.sqrt((res**2).mean())*1e3:.4f} mg (floor {fl*1e3:.4f})")
        elif fam == "colored-noise":
            m2, _ = pose_means(acc, e, 0.0, 1.0)
            r2 = m2 - (g @ A.T + b)
            s = r2.std(axis=0).max()
            mag = e["magnitude"] * 1e-3
            ok = 0.4 * mag - 3 * fl <= s <= 1.6 * mag + 3 * fl
            check(ok, e, f"colored: std over holds {s*1e3:.4f} mg vs magnitude {mag*1e3:.4f} mg (floor {fl*1e3:.4f})")
        elif fam == "out-of-catalogue" and shape == "offset-step":
            ts = e["params"]["step_time_s"]
            step = np.array(e["params"]["step_mg"]) * 1e-3
            before = r[tm < ts - 15].mean(0) if np.any(tm < ts - 15) else r[tm < ts].mean(0)
            after = r[tm > ts + 15].mean(0) if np.any(tm > ts + 15) else r[tm > ts].mean(0)
            err = np.abs(after - before - step).max()
            check(err < 0.25 * np.abs(step).max() + 4 * fl, e,
                  f"offset step: measured {np.round((after-before)*1e3, 4)} vs {np.round(step*1e3, 4)} mg")
        elif fam == "out-of-catalogue" and shape == "flexed-board":
            ks = e["params"]["poses"]
            d = np.array(e["params"]["direction"]) * e["magnitude"] * 1e-3
            others = np.delete(np.arange(len(r)), ks)
            dev = r[ks].mean(0) - r[others].mean(0)
            # the flexed pose also tilts a little (norm-neutral), so compare along the stress direction
            along = dev @ d / (d @ d)
            check(0.6 < along < 1.4 or np.abs(dev - d).max() < 4 * fl, e,
                  f"flexed board: offset of the flexed pose along its direction = {along:.2f} x injected")
        elif fam == "settling" and shape in ("shock-offset-recovery", "hand-thermal"):
            tau = e["params"]["tau_s"]
            odr = e["odr_hz"]
            diffs = []
            for (a_, b_) in tr["holds"]:
                i0 = int(round(a_ * odr))
                i1 = int(round(b_ * odr))
                early = acc[i0 + int(0.1 * tau * odr): i0 + int(1.2 * tau * odr) + 1].mean(0)
                late = acc[i1 - int(0.3 * (b_ - a_) * odr): i1].mean(0)
                diffs.append(np.abs(early - late).max())
            mx = max(diffs)
            mag = e["magnitude"] * 1e-3
            sig = e["noise_sigma_mg"] * 1e-3 / np.sqrt(tau * odr)
            check(0.15 * mag - 4 * sig <= mx <= 1.2 * mag + 4 * sig, e,
                  f"settling: largest early-late hold difference {mx*1e3:.4f} mg vs amplitude {mag*1e3:.4f} mg")
    print(f"\n{checks - fails}/{checks} checks passed" + ("" if not fails else f", {fails} FAILED"))
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
