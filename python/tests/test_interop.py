"""The package in a Python program: the interpreter lock released while samples are solved,
Ctrl-C honoured, pandas used when it is installed and not needed when it is not, and the
merge's report.json read into arrays that agree with the samples."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import truss_mc
from conftest import tool

BIG_JOB = {
    "model": {"prism": {"stages": 5}},
    "seed": 3,
    "cases": [
        {
            "name": "long",
            "samples": 2_000_000,
            "length_errors": {"longeron": {"normal": {"sigma": 0.0063}}},
        }
    ],
}


def test_the_interpreter_runs_while_samples_are_solved() -> None:
    job = truss_mc.Job.from_json(BIG_JOB)
    ticks = [0]
    done = threading.Event()

    def tick() -> None:
        while not done.is_set():
            ticks[0] += 1

    def rate(during) -> float:
        n, t = ticks[0], time.perf_counter()
        during()
        return (ticks[0] - n) / (time.perf_counter() - t)

    thread = threading.Thread(target=tick)
    thread.start()
    try:
        alone = rate(lambda: time.sleep(0.2))
        solving = rate(lambda: job.run(range=(0, 30_000), threads=1))
    finally:
        done.set()
        thread.join()
    # Holding the lock through the solves (about 0.4 s) would stop the other thread but for
    # a switch interval or two (5 ms each); released, it counts on at a like rate.
    assert solving > 0.2 * alone, (solving, alone)


def test_ctrl_c_stops_a_run() -> None:
    job = truss_mc.Job.from_json(BIG_JOB)
    # A real SIGINT, as a terminal's Ctrl-C sends, from a process of its own: a Python timer
    # thread would need the interpreter lock to deliver it.
    # Python raises KeyboardInterrupt only where SIGINT was not ignored when it started (a
    # shell's background job, `cmd &`, starts with it ignored): install the handler an
    # interactive session has.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    started = time.monotonic()
    killer = subprocess.Popen(["sh", "-c", f"sleep 0.3; kill -INT {os.getpid()}"])
    try:
        with pytest.raises(KeyboardInterrupt):
            job.run(threads=2)
    finally:
        killer.wait()
        signal.signal(signal.SIGINT, previous)
    # The whole run takes about a minute; the interrupt is seen within a tick.
    assert time.monotonic() - started < 10


def test_pandas_when_installed(small_job: Path) -> None:
    pandas = pytest.importorskip(
        "pandas",
        reason="pandas is not installed (truss_mc does not need it, scripts/setup.sh does not "
        "install it): target/py-venv/bin/pip install pandas to run this test",
    )
    samples = truss_mc.Job.from_file(small_job).run("normal", inputs=True)
    frame = samples.to_pandas()
    assert list(frame.columns) == samples.fields
    assert frame["theta_p"].to_numpy().tobytes() == samples.theta_p.tobytes()
    inputs = samples.inputs.to_pandas()
    assert isinstance(inputs, pandas.DataFrame) and inputs.shape == (240, 39)


def test_without_pandas_only_to_pandas_needs_it(small_job: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pandas", None)
    samples = truss_mc.Job.from_file(small_job).run("uniform")
    assert len(samples) == 130
    with pytest.raises(ImportError, match="pip install pandas"):
        samples.to_pandas()


def test_report_json_agrees_with_the_samples(small_job: Path, shard_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    tool("mc-merge", str(shard_dir), "--out", str(out), "--no-plots", "--quiet", "--percentiles", "50,95")
    report = truss_mc.read_report(out)
    samples = truss_mc.read_shards(shard_dir)
    assert report.job_id == samples.job_id
    assert report.cases["name"].tolist() == ["normal", "uniform", "backlash"]
    assert report.cases["n"].tolist() == [240, 130, 60]
    for case in ("normal", "uniform", "backlash"):
        theta = np.sort(samples.theta_p[samples.case == case])
        for p in (50.0, 95.0):
            row = (report.percentiles["case"] == case) & (report.percentiles["percentile"] == p)
            # Hyndman–Fan definition 1: the smallest sample x with F_n(x) ≥ p.
            expected = theta[math.ceil(len(theta) * p / 100) - 1]
            assert report.percentiles["value"][row].tolist() == [expected]
            assert report.percentiles["bca_lower"][row][0] <= expected <= report.percentiles["bca_upper"][row][0]
    assert (report.cases["rayleigh_sigma"] > 0).all()
