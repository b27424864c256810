#!/usr/bin/env python3
"""Compare two `dae sweep` results.csv files run by run: status changes, and the runs
whose steps, residual evaluations or factorisations grew by more than 5 %
(issue 26, done-when 4; BENCHMARKS "Session 10 (lead)").

Usage: scripts/s02_compare.py BEFORE.csv AFTER.csv
"""
import csv, sys
def load(p):
    d = {}
    for r in csv.DictReader(open(p)):
        d[(r['solver'], r['formulation'], r['tol'])] = r
    return d
a, b = load(sys.argv[1]), load(sys.argv[2])
keys = ['steps', 'rejected', 'residual_evals', 'jacobian_evals', 'factorizations']
worse = 0; same = 0; n = 0
for k in sorted(a):
    if k not in b: print('missing in new', k); continue
    ra, rb = a[k], b[k]
    if ra['status'] != rb['status']:
        print(k, 'status', ra['status'], ra['error_kind'], '->', rb['status'], rb['error_kind']); continue
    if ra['status'] != 'ok': continue
    n += 1
    flags = []
    for f in ['steps', 'residual_evals', 'factorizations']:
        x, y = float(ra[f]), float(rb[f])
        if y > 1.05 * x and y - x > 5: flags.append(f'{f} {int(x)}->{int(y)} ({y/x:.3f})')
    if all(ra[f] == rb[f] for f in keys): same += 1
    ea, eb = float(ra['err']), float(rb['err'])
    if flags: worse += 1; print(k, '; '.join(flags), f'err {ea:.2e}->{eb:.2e}')
print(f'{n} ok pairs, {same} identical counters, {worse} worse by >5% in steps/evals/LUs')
