"""The results database of `calbench record` (docs/formats.md, "The results database"),
opened with Python's own sqlite3: one row per run and entry, every figure in the long
table, and recording the same run again adds nothing."""
import sqlite3
import subprocess


def _calbench(binary, *args, cwd):
    done = subprocess.run([binary, *map(str, args)], cwd=cwd, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_two_recorded_ci_guard_runs_open_in_sqlite3(binary, root, tmp_path):
    db = tmp_path / "calbench.sqlite"
    scenario = root / "scenarios" / "ci-guard.toml"
    for seed in (1, 2):
        _calbench(binary, "run", scenario, "--trials", 3, "--seed", seed,
                  "--out", tmp_path / f"s{seed}", cwd=tmp_path)
        _calbench(binary, "record", tmp_path / f"s{seed}", "--db", db,
                  "--scenario", scenario, cwd=tmp_path)
    again = _calbench(binary, "record", tmp_path / "s1", "--db", db, "--scenario", scenario,
                      cwd=tmp_path)
    assert "nothing added" in again

    con = sqlite3.connect(db)
    try:
        assert con.execute("PRAGMA user_version").fetchone()[0] == 2
        runs = con.execute("SELECT id, kind, scenario, seed, trials, calbench_version, "
                           "git_commit, cargo_lock_hash, cpu, cores, os, recorded_at "
                           "FROM runs ORDER BY id").fetchall()
        assert [(r[1], r[2], r[3], r[4]) for r in runs] == [
            ("run", "ci-guard", 1, "0..3"), ("run", "ci-guard", 2, "0..3")]
        for r in runs:
            assert r[5] and r[6] and len(r[7]) == 64 and r[8] and r[9] >= 1 and r[10]
            assert r[11].endswith("Z")
        entries = con.execute("SELECT run, entry FROM entries ORDER BY run, entry").fetchall()
        names = ["igg3 / random", "lm / random", "ls / random"]
        assert entries == [(runs[0][0], n) for n in names] + [(runs[1][0], n) for n in names]
        # The long table: each run's validation mean per entry, with its interval.
        rows = con.execute(
            "SELECT run, entry, value, ci_lo, ci_hi FROM figures "
            "WHERE metric = 'validation_after_mm.mean' ORDER BY run, entry").fetchall()
        assert len(rows) == 6
        for _, _, value, lo, hi in rows:
            assert lo < value < hi
        text = con.execute("SELECT scenario_text FROM runs WHERE seed = 1").fetchone()[0]
        assert "trials = 3" in text and "seed = 1" in text
    finally:
        con.close()
