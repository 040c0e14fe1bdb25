#!/usr/bin/env python3
"""blindgen5: independent test-data generator for accelerometer-calibration diagnosis.

python3 generate.py --out DIR --per-family N --seed S
"""
import argparse
import json
import os
import sys
import time
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sim  # noqa: E402
from sim import G0, MAX_ROWS, Part, Session, Thermometer, coarse_grid, fir_causal, write_csv  # noqa: E402

FAMILIES = ['clean', 'drift', 'temperature', 'scale-nonlinearity', 'settling', 'motion', 'colored-noise',
            'out-of-catalogue']
EXPECTED = {'clean': 'none', 'out-of-catalogue': 'honest'}


def plain(x):
    """Make JSON-serialisable plain python values."""
    if isinstance(x, dict):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return plain(x.tolist())
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return round(v, 9) if np.isfinite(v) else None
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    return x


class Log:
    """Builder for one log: a shape function configures it, render() simulates and writes it."""

    def __init__(self, rng):
        self.rng = rng
        self.sess = None
        self.part = None
        self.effects = []      # fn(ctx) -> (N,3) additive reading change in g (before the part's filter)
        self.post = []         # fn(ctx) -> (N,3) additive after the digital filter (pickup)
        self.count_hooks = []  # fn(ctx, counts) -> counts
        self.temp_fn = None    # fn(ctx) -> temperature column (may set ctx['T_die'])
        self.extra = {}

    def session(self, **kw):
        self.sess = Session(self.rng, **kw)
        return self.sess

    def make_part(self, **kw):
        if self.sess is None:
            self.session()
        self.part = Part(self.rng, self.sess.duration, **kw)
        return self.part

    def flat_temp(self):
        """A temperature column that stays at room temperature (no thermal cause present)."""
        rng = self.rng
        T0 = rng.uniform(19.0, 29.0)
        th = Thermometer(rng)

        def fn(ctx):
            tc = coarse_grid(self.sess.duration)
            return th.column(rng, ctx['t'], tc, np.full(len(tc), T0))
        self.temp_fn = fn
        self.extra['temp_column'] = dict(kind='flat', T0=T0, **th.info())
        self.temp_dec = th.dec

    def render(self, path):
        rng = self.rng
        if self.sess is None:
            self.session()
        if self.part is None:
            self.make_part()
        S, P = self.sess, self.part
        N = min(int(np.floor(S.duration * P.fs)) + 1, MAX_ROWS)
        t = np.arange(N) / P.fs
        f = S.specific_force(t)
        f0 = S.specific_force(t, perturbed=False) if S.perts else f
        Af = f @ P.A.T
        hold = S.hold_index(t)
        ctx = dict(t=t, f=f, f0=f0, Af=Af, hold=hold, sess=S, part=P, rng=rng, N=N)
        temp = None
        if self.temp_fn is not None:
            temp = self.temp_fn(ctx)
        delta = np.zeros((N, 3))
        for e in self.effects:
            delta += e(ctx)
        y = Af + P.b + delta
        y += rng.normal(size=(N, 3)) * (P.nd_axes * 1e-6 * np.sqrt(P.fs / 2.0))
        if P.taps is not None:
            y = fir_causal(y, P.taps)
        post = np.zeros((N, 3))
        for e in self.post:
            post += e(ctx)
        y += post
        lim = 2 ** (P.bits - 1)
        counts = np.clip(np.rint(y * P.lsb_per_g), -lim, lim - 1).astype(np.int64)
        for hk in self.count_hooks:
            counts = hk(ctx, counts)
        if P.units == 'counts':
            data = counts.astype(float)
        elif P.units == 'g':
            data = counts / P.lsb_per_g
        else:
            data = counts / P.lsb_per_g * G0
        t_out = P.t0 + t * (1.0 + P.clock_ppm * 1e-6)
        if P.jitter:
            t_out = t_out + rng.uniform(-P.jit_frac, P.jit_frac, N) / P.fs
        write_csv(path, t_out, data, P.units, temp, getattr(self, 'temp_dec', 4))
        # size of the simulated effect in the holds (reading units: g -> mg)
        eff = delta + post + (f - f0) @ P.A.T
        hm = hold >= 0
        en = np.linalg.norm(eff[hm], axis=1) * 1000.0 if hm.any() else np.zeros(1)
        stats = dict(effect_peak_mg=float(en.max()), effect_rms_mg=float(np.sqrt(np.mean(en ** 2))))
        return N, float(t[-1]), stats


def log_rng(seed, family, index):
    return np.random.default_rng([int(seed), zlib.crc32(family.encode()), int(index)])


def make_one(outdir, seed, family, index):
    import shapes
    fam_shapes = shapes.FAMILY_SHAPES[family]
    name, fn = fam_shapes[index % len(fam_shapes)]
    rng = log_rng(seed, family, index)
    L = Log(rng)
    mag, unit, params = fn(rng, L)
    fname = '%s_%03d_%s.csv' % (family, index, name)
    rows, dur, stats = L.render(os.path.join(outdir, fname))
    params = dict(params)
    params.update(stats)
    S = L.sess
    entry = dict(file=fname, family=family, shape=name, expected=EXPECTED.get(family, family),
                 seed=int(seed), index=int(index), magnitude=float(mag), magnitude_unit=unit,
                 poses=int(S.n), duration_s=round(dur, 6), rows=int(rows), params=params,
                 session=dict(mode=S.mode, kind=S.kind, hold_s=[round(float(h), 3) for h in S.holds],
                              move_s=[round(float(m), 3) for m in S.moves],
                              hold_start_s=[round(float(h), 3) for h in S.hs]),
                 part=L.part.info(), temp_column=L.temp_fn is not None, extra=L.extra)
    return plain(entry)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('--out', required=True)
    ap.add_argument('--per-family', type=int, default=12)
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--families', default=','.join(FAMILIES))
    ap.add_argument('--quiet', action='store_true')
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    t0 = time.time()
    manifest = []
    for fam in a.families.split(','):
        for i in range(a.per_family):
            e = make_one(a.out, a.seed, fam, i)
            manifest.append(e)
            if not a.quiet:
                print('%-48s %-26s %8.3g %-10s rows=%6d' % (e['file'], e['shape'], e['magnitude'],
                                                             e['magnitude_unit'], e['rows']), flush=True)
    with open(os.path.join(a.out, 'manifest.json'), 'w') as fh:
        json.dump(manifest, fh, indent=1)
    if not a.quiet:
        print('%d logs in %.1f s' % (len(manifest), time.time() - t0))


if __name__ == '__main__':
    main()
