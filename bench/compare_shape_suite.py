#!/usr/bin/env python3
"""Compare two runs of probecomp_shape_suite, face by face.

Each run is one or more files of the suite's printed rows (the suite's 30 cases, `--draw N --first S` sets, with or
without --regions). Prints each run's distribution (std median and worst, ±2u coverage, the worst region, rows
flagged, the suite's ratio to the reference) and, for the faces both hold, the geometric mean of the std ratios and
every face whose std moved by 2 % or more, whose worst region moved by 3 points or more, or whose flags changed.

    bench/compare_shape_suite.py --before a_suite.txt a_200.txt --after b_suite.txt b_200.txt
"""
import argparse
import math
import statistics


def read_rows(paths):
    rows = {}
    for path in paths:
        with open(path) as f:
            for line in f:
                if line.startswith((' ', 'case', 'SUMMARY')) or '|' not in line:
                    continue
                cells = line.split('|')
                head = cells[0].split()
                if 'FAILED' in line:
                    rows[head[0]] = None
                    continue
                if len(cells) < 5 or len(cells[1].split()) != 4:
                    continue  # not a case's row (a --seeds table, say, which this does not compare)
                a, b, ref = cells[1].split(), cells[2].split(), cells[4].split()
                rows[head[0]] = dict(sigma=float(head[1]), std=float(a[0]), mean=float(a[1]), max=float(a[2]),
                                     flagged=int(a[3]), cov=float(b[0]), worst=float(b[1]), u=float(b[2]),
                                     ratio=float(ref[2]) if len(ref) > 2 else math.nan)
    return rows


def summary(name, rows):
    ok = [r for r in rows.values() if r is not None]
    if not ok:
        print(f"{name}: no case rows read" if not rows else f"{name}: {len(rows)} faces, every one failed")
        return
    stds = [r['std'] for r in ok]
    print(f"{name}: {len(rows)} faces ({len(rows) - len(ok)} failed) | std median {statistics.median(stds):.3f} "
          f"worst {max(stds):.3f} um | 2u overall median {statistics.median(r['cov'] for r in ok):.1f} lowest "
          f"{min(r['cov'] for r in ok):.1f} % | worst region median {statistics.median(r['worst'] for r in ok):.1f} "
          f"lowest {min(r['worst'] for r in ok):.1f} % ({sum(r['worst'] < 88 for r in ok)} under 88 %) | "
          f"flagged {sum(r['flagged'] for r in ok)}")
    ratios = [r['ratio'] for face, r in rows.items()
              if r is not None and face.startswith('S') and not math.isnan(r['ratio'])]
    if ratios:
        print(f"    suite: std over the reference's median {statistics.median(ratios):.3f} worst {max(ratios):.3f}, "
              f"{sum(x > 1.05 for x in ratios)} above 1.05")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--before', nargs='+', required=True)
    parser.add_argument('--after', nargs='+', required=True)
    args = parser.parse_args()
    before, after = read_rows(args.before), read_rows(args.after)
    summary('before', before)
    summary('after', after)
    common = [k for k in before if k in after and before[k] is not None and after[k] is not None]
    for k in before:
        if k in after and (before[k] is None) != (after[k] is None):
            print(f"{k}: failed {'before' if before[k] is None else 'after'}")
    if not common:
        return
    logs = [math.log(after[k]['std'] / before[k]['std']) for k in common]
    print(f"{len(common)} faces in both: geometric mean of the std ratios {math.exp(sum(logs) / len(logs)):.3f}, "
          f"{sum(x < math.log(0.98) for x in logs)} better by 2 % or more, {sum(x > math.log(1.02) for x in logs)} worse")
    for k in common:
        x, y = before[k], after[k]
        if abs(math.log(y['std'] / x['std'])) > math.log(1.02) or abs(y['worst'] - x['worst']) >= 3 or \
                y['flagged'] != x['flagged']:
            print(f"  {k:22s} sigma {x['sigma']:4.1f} | std {x['std']:.3f} -> {y['std']:.3f} | max {x['max']:.2f} -> "
                  f"{y['max']:.2f} | worst region {x['worst']:.1f} -> {y['worst']:.1f} | flagged {x['flagged']} -> "
                  f"{y['flagged']}")


if __name__ == '__main__':
    main()
