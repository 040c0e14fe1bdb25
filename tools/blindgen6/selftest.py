#!/usr/bin/env python3
"""Self-checks of blindgen6 (seeds 1-9 only).

1. determinism: the same seed gives byte-identical CSVs and manifest;
   logs are independent of --per-family / --families (own RNG per log)
2. physics: a still pose read through the nominal part (A, b known from the
   manifest) gives |f| = 1 g within noise, for clean logs
3. manifest fields and values
4. CSV header formats, strictly increasing t, temperature column rules
"""
import csv
import filecmp
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
GEN = os.path.join(HERE, 'generate.py')
G0 = 9.80665
HEADERS = {
    'counts': ['t', 'ax', 'ay', 'az'],
    'g': ['t', 'ax_g', 'ay_g', 'az_g'],
    'mg': ['t', 'ax_mg', 'ay_mg', 'az_mg'],
    'mps2': ['t', 'ax (m/s^2)', 'ay (m/s^2)', 'az (m/s^2)'],
}
FAMILIES = ['clean', 'drift', 'temperature', 'scale-nonlinearity', 'settling', 'motion',
            'colored-noise', 'out-of-catalogue']
FAILS = []


def check(cond, msg):
    if not cond:
        FAILS.append(msg)
        print('FAIL:', msg)


def run(out, seed, per, fams=None):
    cmd = [sys.executable, GEN, '--out', out, '--per-family', str(per), '--seed', str(seed), '--quiet']
    if fams:
        cmd += ['--families', fams]
    subprocess.run(cmd, check=True)
    return json.load(open(os.path.join(out, 'manifest.json')))


def md5(p):
    return hashlib.md5(open(p, 'rb').read()).hexdigest()


def load(path):
    with open(path, newline='') as fh:
        r = csv.reader(fh)
        head = next(r)
        data = np.array([[float(x) for x in row] for row in r])
    return head, data


def main():
    tmp = tempfile.mkdtemp(prefix='bg6_selftest_')
    try:
        a = os.path.join(tmp, 'a')
        b = os.path.join(tmp, 'b')
        c = os.path.join(tmp, 'c')
        ma = run(a, 3, 2)
        mb = run(b, 3, 2)
        # 1. determinism
        check(filecmp.cmp(os.path.join(a, 'manifest.json'), os.path.join(b, 'manifest.json'), shallow=False),
              'manifest not deterministic')
        for m in ma:
            check(md5(os.path.join(a, m['file'])) == md5(os.path.join(b, m['file'])), 'CSV not deterministic: ' + m['file'])
        mc = run(c, 3, 1, 'motion,clean')
        for m in mc:
            check(md5(os.path.join(a, m['file'])) == md5(os.path.join(c, m['file'])),
                  'log depends on the other logs: ' + m['file'])
        print('determinism: %d logs checked' % len(ma))

        # 3. manifest fields
        need = ['file', 'family', 'shape', 'expected', 'seed', 'index', 'magnitude', 'magnitude_unit',
                'poses', 'duration_s', 'rows', 'params', 'part']
        fams = set()
        for m in ma:
            for k in need:
                check(k in m, 'manifest field %s missing in %s' % (k, m.get('file')))
            fams.add(m['family'])
            check(m['family'] in FAMILIES, 'bad family ' + m['family'])
            exp = {'clean': 'none', 'out-of-catalogue': 'honest'}.get(m['family'], m['family'])
            check(m['expected'] == exp, 'bad expected in ' + m['file'])
            for k in ('effect_peak_mg', 'effect_rms_mg'):
                check(k in m['params'], '%s missing in %s' % (k, m['file']))
            for k in ('rate_hz', 'noise_ug_rthz', 'bits', 'range_g', 'filter', 'units', 'A', 'b_mg'):
                check(k in m['part'], 'part.%s missing in %s' % (k, m['file']))
            check(12 <= m['poses'] <= 60, 'pose count out of range in ' + m['file'])
            check(m['rows'] <= 150000, 'too many rows in ' + m['file'])
            if m['family'] == 'clean':
                check(m['magnitude'] == 0 and m['params']['effect_peak_mg'] == 0, 'clean log with an effect: ' + m['file'])
            else:
                check(m['params']['effect_peak_mg'] > 0, 'effect log without effect: ' + m['file'])
        check(fams == set(FAMILIES), 'not all families generated')
        print('manifest: ok' if not FAILS else 'manifest: problems')

        # 4. CSV formats + 2. physics
        for m in ma:
            path = os.path.join(a, m['file'])
            raw = open(path, 'rb').read()
            check(b'\r' not in raw, 'CR in ' + m['file'])
            head, d = load(path)
            units = m['part']['units']
            check(head[:4] == HEADERS[units], 'bad header %s in %s' % (head, m['file']))
            check(len(head) == 4 or head[4:] == ['temp'], 'bad extra columns in ' + m['file'])
            check(len(d) == m['rows'], 'row count mismatch in ' + m['file'])
            check(np.all(np.diff(d[:, 0]) > 0), 't not strictly increasing in ' + m['file'])
            if units == 'counts':
                line = raw.split(b'\n')[1].decode()
                check(all('.' not in x for x in line.split(',')[1:4]), 'counts not integers in ' + m['file'])
            if m['family'] == 'temperature':
                check(len(head) == 5, 'temperature log without temp column: ' + m['file'])
                if len(head) == 5:
                    check(np.ptp(d[:, 4]) >= 1.0, 'temperature does not vary in ' + m['file'])
            elif len(head) == 5 and m['shape'] != 'temp-compensated':
                check(np.ptp(d[:, 4]) < 0.5, 'temp column not flat in non-temperature log ' + m['file'])
            if m['family'] != 'clean':
                continue
            # physics: undo the nominal part on each hold -> |f| = 1 g
            lsb = m['part']['lsb_g']
            scale = {'counts': lsb, 'g': 1.0, 'mg': 1e-3, 'mps2': 1.0 / G0}[units]
            y = d[:, 1:4] * scale
            A = np.array(m['part']['A'])
            bb = np.array(m['part']['b_mg']) * 1e-3
            Ai = np.linalg.inv(A)
            worst = 0.0
            for (t0, t1) in m['holds_t']:
                L = t1 - t0
                sel = (d[:, 0] >= t0 + 0.25 * L) & (d[:, 0] <= t1 - 0.1 * L)
                if sel.sum() < 5:
                    continue
                f = Ai @ (y[sel].mean(axis=0) - bb)
                worst = max(worst, abs(np.linalg.norm(f) - 1.0))
            tol = 5 * m['part']['pose_mean_noise_mg'] * 1e-3 + 0.6 * lsb + 2e-5
            check(worst < tol, '|f| != 1 g in %s: worst %.4f mg > tol %.4f mg' % (m['file'], worst * 1e3, tol * 1e3))
            print('  %-38s |f|-1 worst %.4f mg (tol %.4f)' % (m['file'], worst * 1e3, tol * 1e3))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if FAILS:
        print('%d FAILURES' % len(FAILS))
        sys.exit(1)
    print('selftest OK')


if __name__ == '__main__':
    main()
