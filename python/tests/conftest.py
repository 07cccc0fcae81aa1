"""Shared fixtures of the Python package's tests: the release binaries of the command-line
tools (built by scripts/test.sh before these tests run) and a small job exercising every
kind of case: normal and uniform length errors, and backlash joints with drawn
clearances."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import List

import pytest

REPO = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("TRUSS_MC_BIN_DIR", REPO / "target" / "release"))

SMALL_JOB = {
    "model": {"prism": {"stages": 3}},
    "seed": 20210325,
    "cases": [
        {
            "name": "normal",
            "samples": 240,
            "length_errors": {
                "batten": {"normal": {"sigma": 0.0063}},
                "longeron": {"normal": {"sigma": 0.0063}},
            },
        },
        {
            "name": "uniform",
            "samples": 130,
            "model": {"prism": {"stages": 2}},
            "length_errors": {"longeron": {"uniform": {"low": -0.02, "high": 0.02}}},
        },
        {
            "name": "backlash",
            "samples": 60,
            "model": {"prism": {"stages": 2, "backlash": True}},
            "length_errors": {"longeron": {"normal": {"sigma": 0.0067}}},
            "backlash": {"clearance": {"uniform": {"low": 0.004, "high": 0.017}}},
        },
    ],
}


def binary(name: str) -> Path:
    """A release binary of the workspace; the tests compare against the tools as users run
    them, so a missing binary is a failure, not a skip."""
    path = BIN / name
    if not path.is_file():
        pytest.fail(
            f"{path} is not built: run `cargo build --release -p mc-shard -p mc-merge "
            "-p truss-cli` (scripts/test.sh does) or set TRUSS_MC_BIN_DIR"
        )
    return path


def tool(name: str, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    """Runs a release binary with no batch-scheduler variables set."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("SLURM_", "AWS_BATCH_", "BATCH_TASK_", "MC_SHARD_", "JOB_COMPLETION_"))}
    r = subprocess.run([str(binary(name)), *args], capture_output=True, text=True, env=env)
    if check and r.returncode != 0:
        raise AssertionError(f"{name} {' '.join(args)} exited {r.returncode}: {r.stderr}")
    return r


def cli_error(r: subprocess.CompletedProcess, name: str) -> str:
    """The message of a tool's error line, `NAME: error: MESSAGE`."""
    prefix = f"{name}: error: "
    assert r.stderr.startswith(prefix), r.stderr
    return r.stderr[len(prefix) :].rstrip("\n")


@pytest.fixture(scope="session")
def small_job(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("job") / "job.json"
    path.write_text(json.dumps(SMALL_JOB, indent=1))
    return path


@pytest.fixture(scope="session")
def shard_dir(small_job: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The small job run by `mc-shard run` in three shards."""
    out = tmp_path_factory.mktemp("shards")
    for i in range(3):
        tool("mc-shard", "run", "--job", str(small_job), "--out", str(out), "--shard", f"{i}/3", "--quiet")
    return out


def sample_lines(directory: Path) -> List[dict]:
    """The sample records of every shard file in `directory`, in index order (Python's
    own JSON reader: floats correctly rounded from the shortest form written)."""
    records = []
    for f in sorted(directory.glob("*.jsonl")):
        for line in f.read_text().splitlines():
            r = json.loads(line)
            if r["record"] == "sample":
                records.append(r)
    records.sort(key=lambda r: r["index"])
    return records
