"""pn.lab.run writes the folder `petrinav lab run` writes and returns its
records; an interrupted batch resumes to the same file."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

import petrinav as pn


def read_lines(path):
    return [json.loads(l) for l in path.read_text().splitlines()]


def test_run_returns_the_cli_records(cli, tmp_path):
    ours, theirs = tmp_path / "ours", tmp_path / "theirs"
    records = pn.lab.run("voting", runs=2, out=ours, pictures=False)
    cli.run("lab", "run", "voting", "--runs", "2", "--out", theirs, "--no-pictures")
    assert records == read_lines(theirs / "results.jsonl")
    assert (ours / "results.jsonl").read_text() == (theirs / "results.jsonl").read_text()
    assert (ours / "suite.json").read_text() == (theirs / "suite.json").read_text()
    assert (ours / "index.html").exists()
    assert len(records) == 140 and {"key", "outcome", "time_s", "seed"} <= records[0].keys()
    assert pn.lab.results(ours) == records
    # A folder with results is not overwritten; resume on a finished batch
    # runs nothing and returns the same records.
    with pytest.raises(pn.LabError, match="already holds results"):
        pn.lab.run("voting", runs=2, out=ours, report=False)
    assert pn.lab.run("voting", runs=2, out=ours, resume=True, report=False) == records
    assert "voting" in pn.lab.suites()


def test_shards_and_scenario_files(cli, root, tmp_path):
    part = pn.lab.run("deadlock", runs=1, shard="1/2", out=tmp_path / "part")
    assert 0 < len(part) < len(pn.lab.run("deadlock", runs=1, out=tmp_path / "all", pictures=False))
    scenario = sorted((root / "crates/lab/src/suites/voting/scenarios").glob("*.toml"))[0]
    records = pn.lab.run(scenario, runs=3, out=tmp_path / "file", pictures=False)
    assert len(records) == 3


# With Python's own SIGINT handler, as in test_interrupt.py.
INTERRUPTED_RUN = """
import signal, sys, petrinav as pn
signal.signal(signal.SIGINT, signal.default_int_handler)
try:
    pn.lab.run("voting", runs=20, jobs=1, out=sys.argv[1], report=False)
    print("finished")
except KeyboardInterrupt:
    print("interrupted")
"""


def test_ctrl_c_stops_a_run_cleanly_and_it_resumes(tmp_path):
    out = tmp_path / "v"
    p = subprocess.Popen(
        [sys.executable, "-c", INTERRUPTED_RUN, str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    results = out / "results.jsonl"
    deadline = time.time() + 120
    while time.time() < deadline and not (results.exists() and results.stat().st_size > 2000):
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    sent = time.time()
    stdout, stderr = p.communicate(timeout=60)
    assert time.time() - sent < 10, "the batch did not stop soon after Ctrl-C"
    assert stdout.strip() == "interrupted" and p.returncode == 0, (stdout, stderr)
    text = results.read_text()
    assert text.endswith("\n")  # complete lines only
    done = len(text.splitlines())
    assert 0 < done < 14 * 5 * 20
    records = pn.lab.run("voting", runs=20, jobs=1, out=out, resume=True, report=False)
    full = pn.lab.run("voting", runs=20, out=tmp_path / "w", report=False)
    assert records == full
    assert results.read_text() == (tmp_path / "w" / "results.jsonl").read_text()
