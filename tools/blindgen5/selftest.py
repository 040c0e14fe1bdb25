#!/usr/bin/env python3
"""blindgen5 self-check: physics of the trajectory, manifest fields, CSV format, determinism,
|f| = 1 g in the holds of clean logs.   python3 selftest.py [--keep DIR]"""
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import sim  # noqa: E402
from generate import FAMILIES  # noqa: E402

FAIL = []


def check(cond, msg):
    print(('ok   ' if cond else 'FAIL ') + msg)
    if not cond:
        FAIL.append(msg)


def physics_unit():
    rng = np.random.default_rng(5)
    S = sim.Session(rng, mode='uniform', n_poses=12)
    t = np.concatenate([np.linspace(S.hs[k] + 0.01, S.he[k] - 0.01, 20) for k in range(S.n)])
    f = S.specific_force(t)
    k = S.hold_index(t)
    err = np.max(np.abs(f - S.ups[k]))
    check(err < 1e-6, 'still board reads its sensor-frame up direction, +1 g (max err %.2g g)' % err)
    # pure vertical lift, no rotation: f_z = 1 + z''/g0
    S2 = sim.Session(rng, mode='uniform', n_poses=12)
    S2.q[:] = S2.q[0]
    S2.w[:] = 0.0
    S2.P[:] = 0.0
    S2.lever[:] = 0.0
    T = S2.hs[1] - S2.he[0]
    tt = np.linspace(S2.he[0] + 0.002, S2.hs[1] - 0.002, 400)  # FD straddling the C2 joint: O(h) error
    u = (tt - S2.he[0]) / T
    # z = h * 64 (u - u^2)^3 ; z'' = h*64*(6 (u-u^2)(1-2u)^2 - 6 (u-u^2)^2) / T^2
    s = u - u * u
    zdd = S2.lift[0] * 64 * (6 * s * (1 - 2 * u) ** 2 - 6 * s * s) / T ** 2
    ff = S2.specific_force(tt)
    Rz = sim.q2m(S2.q[0])
    ref = (zdd / sim.G0)[:, None] * Rz.T[:, 2][None, :] + Rz.T[:, 2][None, :]
    err = np.max(np.abs(ff - ref))
    check(err < 1e-5, 'lift acceleration adds to specific force with the right sign (max err %.2g g)' % err)


def run_gen(out, per, seed):
    subprocess.run([sys.executable, os.path.join(HERE, 'generate.py'), '--out', out, '--per-family', str(per),
                    '--seed', str(seed), '--quiet'], check=True)


def digest(d):
    h = hashlib.sha256()
    for f in sorted(os.listdir(d)):
        h.update(f.encode())
        h.update(open(os.path.join(d, f), 'rb').read())
    return h.hexdigest()


def load(path):
    with open(path) as fh:
        head = fh.readline().strip().split(',')
    a = np.loadtxt(path, delimiter=',', skiprows=1, ndmin=2)
    return head, a


def main():
    keep = sys.argv[2] if len(sys.argv) > 2 and sys.argv[1] == '--keep' else None
    physics_unit()
    tmp = tempfile.mkdtemp(prefix='bg5_')
    d1, d2 = os.path.join(tmp, 'a'), os.path.join(tmp, 'b')
    run_gen(d1, 2, 7)
    run_gen(d2, 2, 7)
    check(digest(d1) == digest(d2), 'deterministic in --seed (two runs byte-identical)')
    man = json.load(open(os.path.join(d1, 'manifest.json')))
    check(isinstance(man, list) and len(man) == 2 * len(FAMILIES), 'manifest is a list, one entry per log')
    need = ['file', 'family', 'shape', 'expected', 'seed', 'index', 'magnitude', 'magnitude_unit', 'poses',
            'duration_s', 'rows', 'params']
    exp = {'clean': 'none', 'out-of-catalogue': 'honest'}
    for e in man:
        check(all(k in e for k in need), '%s: manifest fields' % e['file'])
        check(e['expected'] == exp.get(e['family'], e['family']), '%s: expected label' % e['file'])
        head, a = load(os.path.join(d1, e['file']))
        ok_head = head[:4] in (['t', 'ax', 'ay', 'az'], ['t', 'ax (g)', 'ay (g)', 'az (g)'],
                               ['t', 'ax (m/s^2)', 'ay (m/s^2)', 'az (m/s^2)'])
        ok_head &= (len(head) == 4 or head[4] == 'temp')
        check(ok_head, '%s: header %s' % (e['file'], head))
        check(a.shape[0] == e['rows'] <= 150000, '%s: rows %d' % (e['file'], a.shape[0]))
        check(np.all(np.diff(a[:, 0]) > 0), '%s: time increasing' % e['file'])
        check(12 <= e['poses'] <= 40, '%s: %d poses' % (e['file'], e['poses']))
        if e['family'] == 'clean':
            P = e['part']
            A = np.array(P['A'])
            b = np.array(P['bias_g'])
            y = a[:, 1:4]
            if head[1] == 'ax':
                y = y * P['lsb_mg'] / 1000.0
            elif 'm/s^2' in head[1]:
                y = y / sim.G0
            t = (a[:, 0] - a[0, 0])
            norms = []
            for hs, hl in zip(e['session']['hold_start_s'], e['session']['hold_s']):
                m = (t > hs + 0.5) & (t < hs + hl - 0.3)
                if m.sum() > 5:
                    norms.append(np.linalg.norm(np.linalg.solve(A, y[m].mean(0) - b)))
            dev = np.max(np.abs(np.array(norms) - 1.0)) * 1000
            tol = max(0.5, 0.6 * P['lsb_mg']) + 5 * P['noise_density_ug'] * 1e-3 / np.sqrt(1.0)
            check(dev < tol, '%s: |f| = 1 g in the holds (max dev %.3f mg, tol %.2f)' % (e['file'], dev, tol))
    if keep:
        shutil.copytree(d1, keep, dirs_exist_ok=True)
    shutil.rmtree(tmp)
    print('\n%d failures' % len(FAIL))
    return 1 if FAIL else 0


if __name__ == '__main__':
    sys.exit(main())
