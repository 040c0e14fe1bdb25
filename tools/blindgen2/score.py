#!/usr/bin/env python3
"""Score `accelcal diagnose --json` on a directory written by generate.py.

    python3 tools/blindgen2/score.py DIR [DIR ...] [--accelcal PATH] [--json] [--jobs N] [--timeout S]
        [--by-shape] [--by-poses] [--by-evidence] [--by-visibility] [--reuse] [--require-right-visible F]
        [--max-false-alarms F] [--require-ooc-honest F] [--max-refusals N]

For each log in DIR/manifest.json runs the CLI, records verdict, gap.ratio_before,
shrink and wall time (a non-zero exit is a refusal; its message is kept), writes
DIR/results.json and prints per family and overall:
  logs, clearly visible (ratio_before >= 2), right among visible, false alarms on clean
  logs (verdict != none, all clean logs), out-of-catalogue honest (none/unexplained, all
  ooc logs), refusals, median shrink of the right visible ones, slowest log (s).
--by-evidence splits the visible logs by the evidence the diagnosis found for the expected
family (see `evidence`): a miss whose family is weak is one the held-out evidence does not support.
--by-visibility tabulates per family the share right among the logs at or above each gap ratio of
blind_eval's ladder, and the ratio from which 80 % are right (the issue's per-family visibility).
--reuse scores the rows a previous run wrote to DIR/results.json (no CLI run): tables over many
directories, or with other options, without diagnosing again.
Several directories are scored together (their logs pooled; results.json written in each).
The --require/--max options make it a gate: exit status 1, with the reason, when the
overall figures miss them (CI runs it so on a few seeds).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_CLI = os.path.normpath(os.path.join(HERE, "..", "..", "target", "release", "accelcal"))
VISIBLE = 2.0
# Bins of the poses the diagnosis found (--by-poses): a 9-parameter calibration leaves 12 poses 3
# degrees of freedom, so a 3-parameter effect there cannot be tested on withheld poses.
POSE_BINS = ((6, 13), (14, 16), (17, 24), (25, None))
# Smallest evidence (held-out gain) for a family to be named: accelcal's `diagnose::MIN_GAIN`.
MIN_GAIN = 0.3
EVIDENCE_LABELS = ("family leads", "family trails", "family weak", "out of catalogue")
# Gap ratios from which the share right is tabulated (--by-visibility): accelcal's
# `blind_eval::VISIBILITY_LADDER`, and the share that defines "visibility for 80 % right".
VISIBILITY_LADDER = (1.0, 1.25, 1.5, 2.0, 3.0, 5.0, 10.0, 30.0)
RIGHT_SHARE = 0.8


def get(d, path):
    for k in path.split("."):
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def run_one(cli, d, entry, timeout):
    path = os.path.join(d, entry["file"])
    t0 = time.time()
    try:
        p = subprocess.run([cli, "diagnose", "--json", path], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(entry, refused=True, message=f"timeout after {timeout} s", seconds=time.time() - t0)
    secs = time.time() - t0
    if p.returncode != 0:
        msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
        return dict(entry, refused=True, message=" | ".join(msg[-3:])[:400], seconds=secs, exit=p.returncode)
    try:
        js = json.loads(p.stdout)
    except json.JSONDecodeError as e:
        return dict(entry, refused=True, message=f"unparsable JSON: {e}", seconds=secs)
    verdict = js.get("verdict")
    shrink = js.get("shrink")
    if isinstance(verdict, dict):  # {"effect": ..., "shrink": ..., ...}
        if shrink is None:
            shrink = verdict.get("shrink")
        verdict = verdict.get("effect")
    ratio = get(js, "gap.ratio_before")
    poses = js.get("poses") if isinstance(js.get("poses"), int) else None
    return dict(entry, refused=False, verdict=verdict, ratio_before=ratio, shrink=shrink, seconds=secs,
                poses_found=poses, evidence=evidence(js, entry["expected"]))


def family_evidence(c):
    """A candidate's evidence: the better of its held-out gains on withheld pose means and on
    withheld holds (`within_gain`); None when not applicable."""
    if not c.get("applicable"):
        return None
    gains = [g for g in (c.get("heldout_gain"), c.get("within_gain")) if isinstance(g, (int, float))]
    return max(gains) if gains else None


def evidence(js, expected):
    """How the diagnosis' evidence supports the expected family: "family leads" (at least MIN_GAIN,
    no other family more), "family trails" (at least MIN_GAIN, another more), "family weak" (below
    MIN_GAIN: the withheld poses and holds do not show it); "out of catalogue" for those logs; None
    for clean logs."""
    if expected == "none":
        return None
    if expected == "honest":
        return "out of catalogue"
    gains = {c.get("effect"): family_evidence(c) for c in js.get("candidates") or []}
    own = gains.get(expected)
    if own is None or own < MIN_GAIN:
        return "family weak"
    rivals = [g for k, g in gains.items() if k != expected and g is not None]
    return "family leads" if all(own >= g for g in rivals) else "family trails"


def is_right(r):
    if r["refused"]:
        return False
    if r["expected"] == "honest":
        return r["verdict"] in ("none", "unexplained")
    return r["verdict"] == r["expected"]


def at_or_above(r, ratio):
    """The log was answered and its gap ratio (gap.ratio_before) is at least `ratio`."""
    return not r["refused"] and isinstance(r.get("ratio_before"), (int, float)) and r["ratio_before"] >= ratio


def is_visible(r):
    """The log was answered and its gap is clearly visible (gap.ratio_before >= VISIBLE)."""
    return at_or_above(r, VISIBLE)


def summarise(rows):
    vis = [r for r in rows if is_visible(r)]
    right_vis = [r for r in vis if is_right(r)]
    clean = [r for r in rows if r["expected"] == "none" and not r["refused"]]
    ooc = [r for r in rows if r["expected"] == "honest" and not r["refused"]]
    shr = [r["shrink"] for r in right_vis if isinstance(r.get("shrink"), (int, float))]
    return dict(
        logs=len(rows),
        visible=len(vis),
        right_visible=len(right_vis),
        clean_logs=len(clean),
        false_alarms=sum(1 for r in clean if r["verdict"] != "none"),
        ooc_logs=len(ooc),
        ooc_honest=sum(1 for r in ooc if r["verdict"] in ("none", "unexplained")),
        refusals=sum(1 for r in rows if r["refused"]),
        median_shrink=statistics.median(shr) if shr else None,
        slowest_s=round(max((r["seconds"] for r in rows), default=0.0), 2),
        verdicts=dict(sorted(_count(r.get("verdict") or "REFUSED" for r in rows).items())),
    )


def _count(it):
    c = {}
    for x in it:
        c[x] = c.get(x, 0) + 1
    return c


def fmt_row(name, s, w=20):
    fa = f"{s['false_alarms']}/{s['clean_logs']}" if s["clean_logs"] else "-"
    oo = f"{s['ooc_honest']}/{s['ooc_logs']}" if s["ooc_logs"] else "-"
    ms = f"{s['median_shrink']:.3g}" if s["median_shrink"] is not None else "-"
    return (f"{name:<{w}}{s['logs']:>5}{s['visible']:>8}{s['right_visible']:>5}/{s['visible']:<4}"
            f"{fa:>8}{oo:>9}{s['refusals']:>8}{ms:>9}{s['slowest_s']:>9.2f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+", metavar="dir")
    ap.add_argument("--accelcal", default=DEFAULT_CLI)
    ap.add_argument("--json", action="store_true", help="machine output on stdout")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--logs", action="store_true", help="also print one line per log")
    ap.add_argument("--by-shape", action="store_true", help="also a table per family/shape")
    ap.add_argument("--by-poses", action="store_true", help="also a table per count of poses the diagnosis found")
    ap.add_argument("--by-evidence", action="store_true",
                    help="also a table of the visible logs per evidence for the expected family")
    ap.add_argument("--by-visibility", action="store_true",
                    help="also a table per family of the share right from each gap ratio up, and the gap ratio "
                         "from which 80 %% are right")
    ap.add_argument("--reuse", action="store_true",
                    help="score the rows of each DIR/results.json (a previous run) instead of running the CLI")
    ap.add_argument("--require-right-visible", type=float, metavar="F",
                    help="fail unless at least this fraction of the clearly visible logs is right")
    ap.add_argument("--max-false-alarms", type=float, metavar="F",
                    help="fail if more than this fraction of the clean logs is not answered none")
    ap.add_argument("--require-ooc-honest", type=float, metavar="F",
                    help="fail unless at least this fraction of the out-of-catalogue logs is none/unexplained")
    ap.add_argument("--max-refusals", type=int, metavar="N", help="fail if more than N logs are refused")
    a = ap.parse_args(argv)
    if not a.reuse and not os.path.exists(a.accelcal):
        sys.exit(f"no CLI at {a.accelcal}: build it with `cargo build --release -p accelcal-host` or pass --accelcal")
    rows = []
    for d in a.dirs:
        part = reused(d) if a.reuse else run_dir(a, d)
        rows += [dict(r, file=os.path.join(os.path.basename(os.path.normpath(d)), r["file"])) if len(a.dirs) > 1
                 else r for r in part]
    report(a, rows)
    failures = gate_failures(a, summarise(rows))
    for f in failures:
        print(f"GATE FAILED: {f}")
    if failures:
        sys.exit(1)


def run_dir(a, d):
    """Runs the CLI on every log of DIR/manifest.json and writes DIR/results.json."""
    with open(os.path.join(d, "manifest.json")) as fh:
        manifest = json.load(fh)
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        part = list(ex.map(lambda e: run_one(a.accelcal, d, e, a.timeout), manifest))
    write_results(d, part)
    return part


def reused(d):
    """The per-log rows of DIR/results.json (written by a previous run)."""
    path = os.path.join(d, "results.json")
    if not os.path.exists(path):
        sys.exit(f"no {path}: score {d} once without --reuse")
    with open(path) as fh:
        return json.load(fh)["logs"]


def write_results(d, rows):
    """DIR/results.json: the per-family and overall figures and every log's row, for this directory alone."""
    fams = list(dict.fromkeys(r["family"] for r in rows))
    per = {f: summarise([r for r in rows if r["family"] == f]) for f in fams}
    with open(os.path.join(d, "results.json"), "w") as fh:
        json.dump(dict(per_family=per, overall=summarise(rows), logs=rows), fh, indent=1)


def fraction(k, n):
    return k / n if n else None


def gate_failures(a, s):
    """The --require/--max options the overall figures `s` miss, as sentences."""
    out = []
    rv = fraction(s["right_visible"], s["visible"])
    if a.require_right_visible is not None and (rv is None or rv < a.require_right_visible):
        out.append(f"right where visible {s['right_visible']}/{s['visible']} < {a.require_right_visible:.0%}")
    fa = fraction(s["false_alarms"], s["clean_logs"])
    if a.max_false_alarms is not None and fa is not None and fa > a.max_false_alarms:
        out.append(f"false alarms {s['false_alarms']}/{s['clean_logs']} > {a.max_false_alarms:.0%}")
    oo = fraction(s["ooc_honest"], s["ooc_logs"])
    if a.require_ooc_honest is not None and oo is not None and oo < a.require_ooc_honest:
        out.append(f"out-of-catalogue honest {s['ooc_honest']}/{s['ooc_logs']} < {a.require_ooc_honest:.0%}")
    if a.max_refusals is not None and s["refusals"] > a.max_refusals:
        out.append(f"refusals {s['refusals']} > {a.max_refusals}")
    return out


def report(a, rows):
    """Prints the tables (or the JSON with --json) for the pooled rows."""
    fams = []
    for r in rows:
        if r["family"] not in fams:
            fams.append(r["family"])
    per = {f: summarise([r for r in rows if r["family"] == f]) for f in fams}
    overall = summarise(rows)
    if a.json:
        json.dump(dict(per_family=per, overall=overall, logs=rows), sys.stdout, indent=1)
        print()
        return
    print(f"{'family':<20}{'logs':>5}{'visible':>8}{'right/vis':>10}{'f.alarm':>8}{'ooc ok':>9}"
          f"{'refused':>8}{'shrink':>9}{'slowest':>9}")
    for f in fams:
        print(fmt_row(f, per[f]))
    print(fmt_row("overall", overall))
    print()
    if a.by_shape:
        print_groups(rows, lambda r: f"{r['family']}/{r['shape']}", width=36)
    if a.by_poses:
        print_groups(rows, pose_bin, first=[bin_label(lo, hi) for lo, hi in POSE_BINS])
    if a.by_evidence:
        print_evidence(rows)
    if a.by_visibility:
        print_visibility(rows, fams)
    for f in fams:
        print(f"{f}: verdicts {per[f]['verdicts']}")
    if a.logs:
        for r in rows:
            rb = r.get("ratio_before")
            rb = f"{rb:7.2f}" if isinstance(rb, (int, float)) else "      -"
            v = "REFUSED" if r["refused"] else r["verdict"]
            mark = "ok" if is_right(r) else "--"
            print(f"{mark} {r['file']:<44} {r['magnitude']:>9.4g} {r.get('magnitude_unit', ''):<12.12} "
                  f"ratio {rb}  {v:<18} exp {r['expected']:<18} {r['seconds']:6.2f} s")
        print()
    refused = [r for r in rows if r["refused"]]
    for r in refused:
        print(f"refused {r['file']}: {r['message']}")
    print(f"(visible: gap.ratio_before >= {VISIBLE:g}; per-log rows in results.json of {', '.join(a.dirs)})")


def bin_label(lo, hi):
    return f"{lo}-{hi} poses" if hi is not None else f"{lo}+ poses"


def pose_bin(r):
    """The POSE_BINS label of a log's found poses ("refused" without a diagnosis)."""
    n = r.get("poses_found")
    if n is None:
        return "refused"
    for lo, hi in POSE_BINS:
        if n >= lo and (hi is None or n <= hi):
            return bin_label(lo, hi)
    return f"under {POSE_BINS[0][0]} poses"


def print_evidence(rows):
    """The visible logs per evidence for the expected family, and how many misses have it."""
    vis = [r for r in rows if is_visible(r) and r.get("evidence")]
    print_groups(vis, lambda r: r["evidence"], first=EVIDENCE_LABELS)
    missed = [r for r in vis if not is_right(r)]
    backed = sum(1 for r in missed if r["evidence"] in EVIDENCE_LABELS[:2])
    print(f"visible misses: {len(missed)}; the expected family has the evidence (leads or trails) in {backed}, "
          f"is weak in {sum(1 for r in missed if r['evidence'] == 'family weak')}, out of catalogue "
          f"{sum(1 for r in missed if r['evidence'] == 'out of catalogue')}")
    print()


def right_above(rows, ratio):
    """(right, answered) among the logs at or above the gap ratio `ratio`."""
    above = [r for r in rows if at_or_above(r, ratio)]
    return sum(1 for r in above if is_right(r)), len(above)


def visibility_for_share(rows):
    """The smallest VISIBILITY_LADDER ratio from which at least RIGHT_SHARE of the answered logs at or
    above it are right (at least 3 logs there), as blind_eval's `visibility_80`; None if none."""
    for v in VISIBILITY_LADDER:
        right, answered = right_above(rows, v)
        if answered >= 3 and right >= RIGHT_SHARE * answered:
            return v
    return None


def print_visibility(rows, fams):
    """Per family: right/answered among the logs at or above each ladder ratio, and the ratio from
    which RIGHT_SHARE are right."""
    head = "".join(f"{'>= ' + format(v, 'g'):>10}" for v in VISIBILITY_LADDER)
    print(f"{'family':<20}{head}{'80 % right from':>17}")
    for f in fams:
        mine = [r for r in rows if r["family"] == f]
        cells = [f"{k}/{n}" if n else "-" for k, n in (right_above(mine, v) for v in VISIBILITY_LADDER)]
        v80 = visibility_for_share(mine)
        print(f"{f:<20}" + "".join(f"{c:>10}" for c in cells) + f"{'>= ' + format(v80, 'g') if v80 else 'never':>17}")
    print()


def print_groups(rows, key, first=(), width=20):
    """The overall figures per group of rows with the same `key(row)`: the labels `first` in their
    order (those with rows), then the others as they first occur."""
    labels = list(first) + list(dict.fromkeys(key(r) for r in rows if key(r) not in first))
    for label in labels:
        part = [r for r in rows if key(r) == label]
        if part:
            print(fmt_row(label, summarise(part), width))
    print()


if __name__ == "__main__":
    main()
