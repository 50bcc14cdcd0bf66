#!/usr/bin/env python3
# Times the claim query wetgran had before issue 35 (the selection inside
# src/store/sql/claim_next_job.sql of commit f1bbb82) on databases of N pending jobs of the
# orchestrator benchmark's sweep (wetgran-bench orchestrator: 20 grains, 2 periods), built with
# the migrations before the claim queue. One claim ran this selection once; its time is the
# time of one claim. Needs git, Python's sqlite3 and target/release/wetgran (for the specs).
# Usage, from the repository root: python3 scripts/old_claim_query.py [N ...]
import glob, json, os, sqlite3, subprocess, sys, tempfile, time

old_sql = subprocess.run(['git', 'show', 'f1bbb82:src/store/sql/claim_next_job.sql'],
                         capture_output=True, text=True, check=True).stdout
select = old_sql[old_sql.index('(SELECT j.id') + 1: old_sql.rindex('LIMIT 1') + len('LIMIT 1')]
migrations = sorted(glob.glob('migrations/2026112[23]*.sql'))
scene = open('scenes/shaken_wet_2d.toml').read()


def grid(n):
    a = int(n ** 0.5)
    while a > 1 and n % a:
        a -= 1
    return a, n // a


for n in [int(a) for a in sys.argv[1:]] or [500, 1000, 2000]:
    with tempfile.TemporaryDirectory() as d:
        ng, ne = grid(n)
        open(os.path.join(d, 'shaken_wet_2d.toml'), 'w').write(scene)
        sweep = os.path.join(d, 'bench.toml')
        open(sweep, 'w').write(
            '[sweep]\nname = "bench"\nbase = "shaken_wet_2d.toml"\nreplicas = 1\nperiods = 2\n'
            '[scene]\nparticles.count = 20\nbox.size = [7.0, 9.0]\n'
            'engine.min_rebound_speed = 0.03\n'
            '[observe]\ntransient_periods = 1\nsamples_per_period = 20\n'
            f'[[axis]]\nkey = "gamma"\nlog = {{ from = 0.5, to = 20.0, steps = {ng} }}\n'
            f'[[axis]]\nkey = "e_star"\nlog = {{ from = 0.3, to = 4.755, steps = {ne} }}\n')
        c = sqlite3.connect(os.path.join(d, 'old.sqlite'))
        for m in migrations:
            c.executescript(open(m).read())
        c.execute("INSERT INTO sweeps (id, name, file, source, axes, replicas, created_at, "
                  "updated_at) VALUES (1, 'bench', 'f', '', '[]', 1, 0, 0)")
        out = subprocess.run(['target/release/wetgran', 'sweep', 'expand', '--specs', sweep],
                             capture_output=True, text=True, check=True).stdout
        for line in out.splitlines():
            j = json.loads(line)
            c.execute("INSERT INTO jobs (id, spec, created_at) VALUES (?, ?, 0)",
                      (j['id'], json.dumps(j['spec'], separators=(',', ':'))))
            c.execute("INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id) "
                      "VALUES (1, ?, ?, ?, ?)",
                      (j['point'], j['replica'], json.dumps(j['coords']), j['id']))
        c.commit()
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            c.execute(select.replace('?3', '1')).fetchone()
            times.append(time.perf_counter() - t0)
        times.sort()
        print(f'N = {ng * ne}: one claim (old query) {times[1]:.3f} s, median of 3 '
              f'(SQLite {sqlite3.sqlite_version})', flush=True)
