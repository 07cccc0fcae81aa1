"""Errors cross into Python as truss_mc.errors exceptions with the messages, exit codes and
JSON paths of the command-line tools; nothing panics."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import truss_mc
from conftest import SMALL_JOB, cli_error, tool


def bad_job(tmp_path: Path, edit) -> Path:
    job = json.loads(json.dumps(SMALL_JOB))
    edit(job)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(job))
    return path


@pytest.mark.parametrize(
    ("edit", "json_path"),
    [
        (lambda j: j["cases"][0]["length_errors"].update(longron={"normal": {"sigma": 0.01}}), "cases[0].length_errors.longron"),
        (lambda j: j["cases"][1].update(samples=0), "cases[1].samples"),
        (lambda j: j["cases"][2]["model"]["prism"].update(stages=1001), "cases[2].model.prism.stages"),
        (lambda j: j["cases"][0]["length_errors"].update(batten={"normal": {"sigma": 5.0}}), "cases[0].length_errors.batten"),
        (lambda j: j.update(sed=1), "sed"),
    ],
)
def test_a_bad_job_raises_with_the_clis_message_and_json_path(tmp_path: Path, edit, json_path) -> None:
    path = bad_job(tmp_path, edit)
    r = tool("mc-shard", "plan", "--job", str(path), check=False)
    assert r.returncode == 3
    with pytest.raises(truss_mc.InvalidInputError) as e:
        truss_mc.Job.from_file(str(path))
    assert str(e.value) == cli_error(r, "mc-shard")
    assert e.value.exit_code == 3 and isinstance(e.value, ValueError)
    assert e.value.json_path == json_path
    if json_path:
        assert f"{path}: {json_path}: " in str(e.value)


def test_a_missing_file_is_an_os_error(tmp_path: Path) -> None:
    path = tmp_path / "none.json"
    r = tool("mc-shard", "plan", "--job", str(path), check=False)
    with pytest.raises(truss_mc.TrussIOError) as e:
        truss_mc.Job.from_file(path)
    assert (str(e.value), e.value.exit_code, r.returncode) == (cli_error(r, "mc-shard"), 4, 4)
    assert isinstance(e.value, OSError)
    with pytest.raises(truss_mc.TrussIOError):
        truss_mc.Model.from_file(path)


def test_unknown_cases_samples_and_ranges_are_usage_errors(small_job: Path) -> None:
    job = truss_mc.Job.from_file(small_job)
    for case, sample in (("nope", 0), ("uniform", 130)):
        r = tool("mc-shard", "reproduce", "--job", str(small_job), "--case", case, "--sample", str(sample), check=False)
        with pytest.raises(truss_mc.UsageError) as e:
            job.reproduce(case, sample)
        assert (str(e.value), e.value.exit_code, r.returncode) == (cli_error(r, "mc-shard"), 2, 2)
    with pytest.raises(truss_mc.UsageError, match="range 0..431 is outside the job's samples 0..430"):
        job.run(range=(0, 431))
    with pytest.raises(truss_mc.UsageError, match="no case"):
        job.inputs("nope")
    with pytest.raises(truss_mc.UsageError, match="threads"):
        job.run(threads=0)


def test_bad_solves_and_prisms(tmp_path: Path) -> None:
    model = truss_mc.prism(stages=2)
    path = tmp_path / "m.json"
    path.write_text(model.to_json())
    for member, value in (("longeron.1.0", 100.0), ("nope", 0.01)):
        r = tool("truss", "solve", str(path), f"--length-error={member}={value}", check=False)
        with pytest.raises(truss_mc.UsageError) as e:
            truss_mc.solve(model, {member: value})
        cli = cli_error(r, "truss")
        prefix = f'--length-error "{member}={value}": '
        assert cli.startswith(prefix) and r.returncode == 2
        assert str(e.value) == f'length_errors["{member}"]: ' + cli[len(prefix) :]
    with pytest.raises(truss_mc.UsageError, match="not a finite number"):
        truss_mc.solve(model, {"batten.0.0": float("nan")})
    with pytest.raises(truss_mc.InvalidInputError) as e:
        truss_mc.prism(stages=3, side=-1.0)
    assert e.value.json_path == "prism.side"
    with pytest.raises(truss_mc.InvalidInputError) as e:
        truss_mc.prism(stages=3, backlash={"clearence": 0.01})
    assert e.value.json_path == "prism.backlash"
    with pytest.raises(truss_mc.InvalidInputError, match="<string>: line 1, column 11: invalid type"):
        truss_mc.Model.from_json('{"nodes": 3}')


def test_damaged_and_foreign_shards_do_not_verify(small_job: Path, shard_dir: Path, tmp_path: Path) -> None:
    files = sorted(shard_dir.glob("*.jsonl"))
    lines = files[0].read_text().splitlines(keepends=True)
    damaged = tmp_path / files[0].name
    damaged.write_text("".join(lines[:3]) + lines[3].replace('"theta_p":', '"theta_p":1') + "".join(lines[4:]))
    with pytest.raises(truss_mc.VerificationError, match=r"sha256 .* does not match"):
        truss_mc.read_shards(damaged)
    torn = tmp_path / "torn" / files[0].name
    torn.parent.mkdir()
    torn.write_text("".join(lines[:120]))  # the begin line, 100 samples, a checkpoint, 18 more
    with pytest.raises(truss_mc.VerificationError, match="incomplete"):
        truss_mc.read_shards(torn.parent)
    assert len(truss_mc.read_shards(torn.parent, partial=True)) == 100  # up to the checkpoint
    other = json.loads(small_job.read_text())
    other["seed"] = 1
    other_job = tmp_path / "other.json"
    other_job.write_text(json.dumps(other))
    tool("mc-shard", "run", "--job", str(other_job), "--out", str(tmp_path / "other"), "--shard", "1/3", "--quiet")
    with pytest.raises(truss_mc.VerificationError, match="shards of two jobs"):
        truss_mc.read_shards([files[0], *(tmp_path / "other").glob("*.jsonl")])


def test_a_fifo_is_refused_before_it_is_opened(tmp_path: Path) -> None:
    """``read_shards`` and ``read_report`` check the file type before they open a file, as
    ``mc-merge`` does: a FIFO (which an open would wait on forever) is invalid input at once."""
    import os

    fifo = tmp_path / "shard.jsonl"
    os.mkfifo(fifo)
    with pytest.raises(truss_mc.InvalidInputError, match="not a regular file"):
        truss_mc.read_shards(fifo)
    with pytest.raises(truss_mc.InvalidInputError, match="not a regular file"):
        truss_mc.read_report(fifo)


def test_arguments_of_the_wrong_type_are_named(small_job: Path, tmp_path: Path) -> None:
    """A bool is not 1 mm, a list or a string is not a mapping of length errors, a thread
    count out of range is the tools' usage error, a prism option that is NaN names its
    field, and a malformed report.json is invalid input, not a KeyError."""
    model = truss_mc.prism(stages=2)
    with pytest.raises(TypeError, match=r'length_errors\["batten.0.0"\]: expected a number, got bool'):
        truss_mc.solve(model, {"batten.0.0": True})
    for wrong in (["batten.0.0", 0.01], "batten.0.0"):
        with pytest.raises(TypeError, match="length_errors: expected a mapping"):
            truss_mc.solve(model, wrong)  # type: ignore[arg-type]
    job = truss_mc.Job.from_file(small_job)
    for threads in (-1, 0, 1025, True):
        with pytest.raises(truss_mc.UsageError, match="threads must be 1 to 1024"):
            job.run(threads=threads)
    with pytest.raises(truss_mc.InvalidInputError, match="prism.side: nan is not a finite number") as e:
        truss_mc.prism(stages=3, side=float("nan"))
    assert e.value.json_path == "prism.side"
    with pytest.raises(TypeError, match="prism.height: expected a number"):
        truss_mc.prism(stages=3, height=True)
    report = tmp_path / "report.json"
    for text in ('{"format": "truss-mc-merge-report"}', '{"cases": []}', "[1, 2]", "not json"):
        report.write_text(text)
        with pytest.raises(truss_mc.InvalidInputError, match="report"):
            truss_mc.read_report(report)
