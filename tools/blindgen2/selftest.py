#!/usr/bin/env python3
"""Checks of the generator against its own physics (never against accelcal):

    python3 tools/blindgen2/selftest.py

* clean sessions: an own 9-parameter fit (lower-triangular Ka, bias; Gauss-Newton) of the
  true hold means leaves a residual at the noise level (ratio to sigma/sqrt(n) in 0.5-2);
* flicker: Allan deviation plateau ~ 0.664 B; random walk: Allan deviation ~ K sqrt(tau/3);
  Gauss-Markov: std ~ sigma; tremor: rms ~ amplitude; mains: alias above 1 Hz at every rate;
* every family/shape generates (small mode) and its hold rows are still in the clean case.
Prints one line per check and exits non-zero on a failure.
"""

import math
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import generate as G  # noqa: E402
import injectors as inj  # noqa: E402
from physics import RATES, Session, render  # noqa: E402

FAIL = []


def check(name, ok, detail):
    print(f"{'ok  ' if ok else 'FAIL'} {name}: {detail}")
    if not ok:
        FAIL.append(name)


def fit9(means):
    """Residual |A (m - c)| - 1 of the 9-parameter model after Gauss-Newton."""
    c0 = means.mean(0)
    x = np.array([1, 0, 1, 0, 0, 1, *c0], dtype=float)

    def res(x):
        A = np.array([[x[0], 0, 0], [x[1], x[2], 0], [x[3], x[4], x[5]]])
        return np.linalg.norm((means - x[6:]) @ A.T, axis=1) - 1

    for _ in range(40):
        r = res(x)
        J = np.empty((len(r), 9))
        for j in range(9):
            d = np.zeros(9)
            d[j] = 1e-7
            J[:, j] = (res(x + d) - r) / 1e-7
        x = x - np.linalg.lstsq(J, r, rcond=None)[0]
    return res(x)


def allan(x, fs, m):
    """Non-overlapping Allan deviation of x at cluster size m samples."""
    n = len(x) // m
    y = x[: n * m].reshape(n, m).mean(1)
    return math.sqrt(0.5 * np.mean(np.diff(y) ** 2))


class Bare:
    """A minimal stand-in for Session (a long static record) for the noise injectors."""

    def __init__(self, fs, seconds):
        self.fs, self.N = fs, int(fs * seconds)
        self.duration = seconds
        self.t_true = np.arange(self.N) / fs
        self.noise = np.zeros((self.N, 3))
        self.holds = [(0, self.N)]
        self.f = np.tile([0.0, 0.0, 1.0], (self.N, 1))


def main():
    # 1. clean sessions are inside the model
    for i, part in enumerate(["mpu6050", "adxl355", "adxl345", "lis3dh"]):
        rng = np.random.default_rng(1000 + i)
        s = Session(rng, small=False, part=part, max_samples=60_000)
        t, v, h, fmt = render(s, "g")
        skip = 0.2
        means = np.array([v[a + int(skip * (b - a)):b].mean(0) for a, b in s.holds])
        n = np.mean([(b - a) * (1 - skip) for a, b in s.holds])
        sd = np.mean([v[a:b].std(0).mean() for a, b in s.holds])
        r = fit9(means)
        # a least-squares residual keeps (P - 9) / P of the variance of the pose means
        ratio = r.std() / (sd / math.sqrt(n) * math.sqrt((s.n_poses - 9) / s.n_poses))
        check(f"clean {part}", 0.5 < ratio < 2.0,
              f"{s.n_poses} poses {s.fs:g} Hz: residual {1e3 * r.std():.4f} mg vs sigma/sqrt(n) "
              f"{1e3 * sd / math.sqrt(n):.4f} mg (ratio {ratio:.2f} after the (P-9)/P dof correction)")

    rng = np.random.default_rng(7)
    # 2. flicker plateau
    s = Bare(50.0, 20000)
    inj.colored_flicker(s, rng, 200.0)
    ad = [allan(s.noise[:, 0], s.fs, m) for m in (500, 2500, 12500)]
    check("flicker Allan plateau", all(0.6 * 0.664 * 200 < 1e6 * a < 1.5 * 0.664 * 200 for a in ad),
          f"B 200 ug: Allan dev at 10/50/250 s = {', '.join(f'{1e6 * a:.0f}' for a in ad)} ug (0.664 B = 133)")
    # 3. random walk slope
    s = Bare(50.0, 20000)
    inj.colored_random_walk(s, rng, 20.0)
    tau = 1000.0
    a = np.mean([allan(s.noise[:, i], s.fs, int(tau * s.fs)) for i in range(3)])
    want = 20e-6 * math.sqrt(tau / 3)
    check("random walk Allan", 0.6 < a / want < 1.5, f"K 20 ug/rts: Allan dev at 1000 s {1e6 * a:.0f} ug, expected {1e6 * want:.0f}")
    # 4. Gauss-Markov std
    s = Bare(50.0, 4000)
    inj.colored_gauss_markov(s, rng, 300.0)
    sd = s.noise.std(0).mean()
    check("Gauss-Markov std", 0.6 < sd / 300e-6 < 1.4, f"sigma 300 ug: std {1e6 * sd:.0f} ug")
    # 5. tremor rms
    s = Bare(200.0, 60)
    inj.motion_tremor(s, rng, 20.0)
    hp = s.f - s.f.mean(0)
    check("tremor rms", 1.0 < 1e3 * hp.std(0).mean() / 20.0 < 2.2,
          f"20 mg tremor (+ hand drift 0.5-1.5x): rms {1e3 * hp.std(0).mean():.1f} mg per axis")
    # 6. mains alias
    worst = 1e9
    for fs in RATES:
        for k in range(20):
            s = Bare(fs, 2)
            p = inj.ooc_mains(s, np.random.default_rng(k), 1.0)
            worst = min(worst, p["alias_hz"])
    check("mains alias", worst > 1.0, f"smallest alias over all rates {worst:.2f} Hz")
    # 7. every shape generates
    with tempfile.TemporaryDirectory() as d:
        n = 0
        for fam, (exp, shapes) in G.FAMILIES.items():
            for shape in shapes:
                m = G.generate_one(d, fam, shape, 12345 + n, 0.5, True, n)
                n += 1
                ok = os.path.getsize(os.path.join(d, m["file"])) > 1000 and len(m["hold_rows"]) == m["poses"]
                if not ok:
                    check(f"generate {fam}/{shape}", False, str(m)[:200])
        check("all shapes generate", True, f"{n} shapes in small mode")
    if FAIL:
        sys.exit(f"{len(FAIL)} failed: {', '.join(FAIL)}")


if __name__ == "__main__":
    main()
