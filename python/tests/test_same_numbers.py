"""The package's numbers are the command-line tools' numbers, bit for bit: a job run in
Python against the shard lines `mc-shard run` writes, the drawn inputs against
`mc-shard inputs`, a reproduced sample against `mc-shard reproduce`, a solve against
`truss solve`, and shards read back against the run; and none of them depends on the thread
count."""

from __future__ import annotations

import csv
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

import truss_mc
from conftest import SMALL_JOB, sample_lines, tool

FLOAT_FIELDS = (
    "theta_p",
    "tan_theta_x",
    "tan_theta_y",
    "decenter_x",
    "decenter_y",
    "decenter",
    "despace",
    "residual",
    "slack_cables",
    "loose_joints",
)


def bits(x: float) -> bytes:
    return struct.pack("<d", x)


def assert_matches_lines(samples: truss_mc.Samples, records: list) -> None:
    """Every field of every sample line equals the array's entry (floats bit for bit); a
    field a line lacks is NaN (numbers) or empty (text) in the arrays."""
    assert len(samples) == len(records)
    fields = set().union(*(r.keys() for r in records)) - {"record"}
    assert fields <= set(samples.fields), fields - set(samples.fields)
    for i, r in enumerate(records):
        for f in samples.fields:
            value = samples[f][i]
            if f not in r:
                assert (math.isnan(value) if samples[f].dtype.kind == "f" else value == ""), (i, f, value)
            elif samples[f].dtype.kind == "f":
                assert bits(float(value)) == bits(float(r[f])), (i, f, value, r[f])
            else:
                assert value == r[f], (i, f, value, r[f])


def assert_same_arrays(a: truss_mc.Samples, b: truss_mc.Samples) -> None:
    assert a.fields == b.fields
    for f in a.fields:
        x, y = a[f], b[f]
        assert x.dtype == y.dtype, f
        if x.dtype.kind == "f":
            assert np.array_equal(np.isnan(x), np.isnan(y)), f
            assert x[~np.isnan(x)].tobytes() == y[~np.isnan(y)].tobytes(), f
        else:
            assert np.array_equal(x, y), f


def test_run_equals_the_shard_lines(small_job: Path, shard_dir: Path) -> None:
    job = truss_mc.Job.from_file(small_job)
    records = sample_lines(shard_dir)
    samples = job.run(threads=2)
    assert job.samples == len(records) == 430
    assert_matches_lines(samples, records)
    # Every kind of line is covered: joints' counts, and floats in every float field.
    assert not np.isnan(samples.loose_joints[-60:]).any()
    assert np.isnan(samples.loose_joints[:-60]).all()
    assert samples.index.tolist() == list(range(430))
    for f in FLOAT_FIELDS[:4]:
        assert samples[f].dtype == np.float64


def test_the_thread_count_changes_nothing(small_job: Path) -> None:
    job = truss_mc.Job.from_file(small_job)
    one = job.run(threads=1, inputs=True)
    for threads in (2, 3, 7):
        other = job.run(threads=threads, inputs=True)
        assert_same_arrays(one, other)
        assert one.inputs.values.tobytes() == other.inputs.values.tobytes()
    # A case, and a range across two cases, are the whole run's slices.
    part = job.run(range=(201, 377), threads=3)
    for f in part.fields:
        x, y = part[f], one[f][201:377]
        assert x.tobytes() == y.tobytes() if x.dtype.kind == "f" else x.tolist() == y.tolist(), f
    case = job.run("uniform", threads=2)
    assert case.index.tolist() == list(range(240, 370))
    assert case.theta_p.tobytes() == one.theta_p[240:370].tobytes()


def test_shards_read_back_equal_the_run(small_job: Path, shard_dir: Path) -> None:
    job = truss_mc.Job.from_file(small_job)
    read = truss_mc.read_shards(shard_dir)
    assert read.job_id == job.id
    assert [c["name"] for c in read.cases] == [c["name"] for c in SMALL_JOB["cases"]]
    assert_same_arrays(read, job.run())
    files = sorted(shard_dir.glob("*.jsonl"))
    # Files given one by one, in any order, with a duplicate: the same samples.
    again = truss_mc.read_shards([files[2], files[0], files[1], files[0]])
    assert_same_arrays(read, again)


def test_inputs_equal_mc_shard_inputs(small_job: Path, tmp_path: Path) -> None:
    job = truss_mc.Job.from_file(small_job)
    for case in (None, "backlash"):
        out = tmp_path / f"inputs-{case}.csv"
        args = ["inputs", "--job", str(small_job), "-o", str(out)]
        tool("mc-shard", *args, *(["--case", case] if case else []))
        with open(out, newline="") as f:
            rows = list(csv.reader(f))
        inputs = job.inputs(case)
        assert rows[0] == ["index", "case", "sample", *inputs.columns]
        assert len(rows) - 1 == len(inputs)
        for i, row in enumerate(rows[1:]):
            assert [int(row[0]), row[1], int(row[2])] == [inputs.index[i], inputs.case[i], inputs.sample[i]]
            for j, cell in enumerate(row[3:]):
                v = inputs.values[i, j]
                assert (math.isnan(v) if cell == "" else bits(v) == bits(float(cell))), (i, j, cell, v)
    # The inputs a run returns are these rows.
    run = job.run(inputs=True)
    assert run.inputs.values.tobytes() == job.inputs().values.tobytes()
    assert run.inputs.clearances.shape == (430, 12)  # 6 joints per stage
    assert np.isnan(run.inputs.clearances[:370]).all() and not np.isnan(run.inputs.clearances[370:]).any()


@pytest.mark.parametrize(("case", "sample"), [("normal", 0), ("uniform", 77), ("backlash", 59)])
def test_reproduce_equals_mc_shard_reproduce(small_job: Path, case: str, sample: int) -> None:
    job = truss_mc.Job.from_file(small_job)
    base = ["reproduce", "--job", str(small_job), "--case", case, "--sample", str(sample)]
    assert job.reproduce(case, sample) == tool("mc-shard", *base).stdout
    detail = json.loads(tool("mc-shard", *base, "--detail").stdout)
    assert job.reproduce(case, sample, detail=True) == detail
    line = json.loads(detail["line"])
    index = line["index"]
    run = job.run(range=(index, index + 1))
    assert bits(run.theta_p[0]) == bits(line["theta_p"])


def test_solve_equals_truss_solve(tmp_path: Path) -> None:
    model = truss_mc.prism(stages=4, backlash=True)
    path = tmp_path / "model.json"
    path.write_text(model.to_json())
    errors = {"longeron.1.0": 0.012, "batten.2.1": -0.007, "diagonal.3.2.a": 0.003}
    cli = json.loads(tool("truss", "solve", str(path), *[f"--length-error={k}={v!r}" for k, v in errors.items()]).stdout)
    s = truss_mc.solve(truss_mc.Model.from_file(path), errors)
    for f in ("theta_p", "tan_theta_x", "tan_theta_y", "decenter_x", "decenter_y", "decenter", "despace", "residual"):
        assert bits(getattr(s, f)) == bits(cli[f]), f
    assert (s.iterations, s.factorisations) == (cli["iterations"], cli["factorisations"])
    assert s.node_ids == list(cli["displacements"])
    assert s.displacements.tobytes() == np.array(list(cli["displacements"].values())).tobytes()
    assert s.forces.tobytes() == np.array(list(cli["forces"].values())).tobytes()
    assert s.slack_cables == cli["slack_cables"]
    assert s.joint_ids == list(cli["joints"])
    assert s.joint_contact.tolist() == [j["contact"] for j in cli["joints"].values()]
    assert s.joint_loose.tolist() == [j["loose"] for j in cli["joints"].values()]
    assert s.joint_offsets.tolist() == [j["offset"] for j in cli["joints"].values()]
    assert s.force("longeron.1.0") == cli["forces"]["longeron.1.0"]
    # The prism the job format takes is `truss model prism`'s.
    assert model.to_json() == tool("truss", "model", "prism", "--stages", "4", "--backlash").stdout
