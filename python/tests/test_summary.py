"""The merge's statistics from Python are mc-merge's, computed by its own code: the summary of
a job run in-process and of shards read back is the report.json that `mc-merge` writes for
the same samples, byte for byte, its answer lines are the ones the console ends with, and its
arrays hold report.json's numbers; a run of one case is partial as `mc-merge --allow-partial`
makes it."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import truss_mc
from conftest import tool

# A σ-series (for the allowable σ) of two small cases, and a case of another model.
SWEEP_JOB = {
    "model": {"prism": {"stages": 2}},
    "seed": 7,
    "cases": [
        {
            "name": "s1",
            "samples": 400,
            "length_errors": {"batten": {"normal": {"sigma": 0.0033}}, "longeron": {"normal": {"sigma": 0.0033}}},
        },
        {
            "name": "s2",
            "samples": 300,
            "length_errors": {"batten": {"normal": {"sigma": 0.0063}}, "longeron": {"normal": {"sigma": 0.0063}}},
        },
        {
            "name": "tall",
            "samples": 200,
            "model": {"prism": {"stages": 4}},
            "length_errors": {"longeron": {"normal": {"sigma": 0.0063}}},
        },
    ],
}

FAST = ("--replicates", "300", "--gof-replicates", "99")


def same(array: np.ndarray, numbers: list) -> None:
    """The array holds report.json's numbers exactly, NaN where the report has null."""
    expected = np.array([math.nan if x is None else x for x in numbers], dtype=np.float64)
    np.testing.assert_array_equal(array, expected)


def settings(**more):
    return dict(replicates=300, gof_replicates=99, **more)


@pytest.fixture(scope="module")
def sweep(tmp_path_factory: pytest.TempPathFactory):
    """The job, its shards (two processes), and mc-merge's report.json and console."""
    root = tmp_path_factory.mktemp("sweep")
    job = root / "job.json"
    job.write_text(json.dumps(SWEEP_JOB))
    shards = root / "shards"
    for i in range(2):
        tool("mc-shard", "run", "--job", str(job), "--out", str(shards), "--shard", f"{i}/2", "--quiet")
    report = root / "report"
    console = tool("mc-merge", str(shards), "--out", str(report), *FAST).stdout
    return job, shards, report, console


def test_a_run_in_process_gives_the_merges_report(sweep) -> None:
    job, shards, report, console = sweep
    written = (report / "report.json").read_text()
    summary = truss_mc.Job.from_file(job).run(threads=2).summary(**settings())
    assert summary.text == written
    # The console ends with the answer, then the report's path.
    assert summary.answer.text is not None
    assert console.endswith(f"{summary.answer.text}\nreport: {report / 'report.html'}\n"), console
    # Shards read back give the same, whatever the thread count.
    again = truss_mc.read_shards(shards).summary(threads=1, **settings())
    assert again.text == written


def test_the_summarys_arrays_are_report_json_numbers(sweep) -> None:
    job, _, report, _ = sweep
    data = json.loads((report / "report.json").read_text())
    s = truss_mc.Job.from_file(job).run().summary(**settings())
    # Percentiles with their intervals, in report.json's order.
    rows = [(c["name"], p) for c in data["cases"] for p in c["percentiles"]]
    assert list(s.percentiles["case"]) == [name for name, _ in rows]
    same(s.percentiles["value"], [p["value"] for _, p in rows])
    same(s.percentiles["bca_lower"], [p["bca"]["lower"] for _, p in rows])
    same(s.percentiles["order_upper"], [p["order_statistic"]["upper"] for _, p in rows])
    # The Rayleigh law and its verdicts.
    assert list(s.cases["gof_verdict"]) == [c["gof"]["verdict"] for c in data["cases"]]
    same(s.cases["ad_p_value"], [c["gof"]["ad"]["p_value"] for c in data["cases"]])
    ray = [(c["name"], p) for c in data["cases"] for p in c["rayleigh"]["percentiles"]]
    same(s.rayleigh["value"], [p["value"]["value"] for _, p in ray])
    # The allowable σ of the σ-series s1, s2, with its interval.
    (series,) = data["sweep"]["sigma_series"]
    a = series["allowable_sigma"]["through_origin"]
    same(s.allowable_sigma["value"], [a["value"]])
    same(s.allowable_sigma["lower"], [a["lower"]])
    same(s.answer.allowable_sigma["upper"], [a["upper"]])
    # The answer: each case against the target, the verdicts with Holm's adjustment.
    target = data["settings"]["target_angle"]
    assert s.answer.target_angle == target
    for c, against in zip(data["cases"], s.answer.cases["against"]):
        p95 = next(p["value"] for p in c["percentiles"] if p["percentile"] == 95)
        assert against == ("above" if p95 > target else "within")
    v = data["answer"]["rayleigh"]
    same(s.answer.rayleigh["holm_p_value"], [c["holm_p_value"] for c in v["cases"]])
    assert s.answer.tested == 3 and math.isclose(s.answer.expected_by_chance, 3 * 0.05)
    names = [c["name"] for c in data["cases"]]
    assert s.answer.above == [n for n, a in zip(names, s.answer.cases["against"]) if a == "above"]
    assert sorted(s.answer.within + s.answer.above) == sorted(names)


def test_a_run_of_one_case_is_partial_like_allow_partial(sweep, tmp_path: Path) -> None:
    job, _, _, _ = sweep
    j = truss_mc.Job.from_file(job)
    s = j.run("s2").summary(**settings())
    assert s.data["coverage"]["complete"] is False
    shards = tmp_path / "s2"
    tool("mc-shard", "run", "--job", str(job), "--out", str(shards), "--range", "400..700", "--quiet")
    out = tmp_path / "report"
    tool("mc-merge", str(shards), "--out", str(out), "--allow-partial", *FAST)
    assert s.text == (out / "report.json").read_text()
    # Asked for the whole job, the merge's refusal: the other cases are missing.
    with pytest.raises(truss_mc.VerificationError, match="300 of 900 samples present"):
        j.run("s2").summary(allow_partial=False, **settings())
    # The merge's settings are refused as mc-merge refuses them, naming the flag.
    with pytest.raises(truss_mc.UsageError, match="--target-angle"):
        j.run("s2").summary(target_angle=2.0)
    # Samples built by hand have nothing to summarise.
    with pytest.raises(truss_mc.UsageError, match="summary"):
        truss_mc.Samples({"index": np.array([0])}).summary()


def test_the_defaults_are_mc_merges(sweep, tmp_path: Path) -> None:
    # Every keyword left out is mc-merge's own default (taken from its settings, not copied):
    # the summary is the report.json of a merge given no flag.
    job, shards, _, _ = sweep
    out = tmp_path / "report"
    tool("mc-merge", str(shards), "--out", str(out), "--quiet")
    assert truss_mc.read_shards(shards).summary().text == (out / "report.json").read_text()


# The σ-series of SWEEP_JOB's first two cases, held to a three-line alignment budget (as
# jobs/budget-5.json states it, tightened so that the small truss fails one line).
BUDGET_JOB = {
    "model": {"prism": {"stages": 2}},
    "seed": 11,
    "budget": {"theta_p": {"arcsec": 20}, "decenter": {"um": 20}, "despace": {"mm": 0.03}, "percentile": 95},
    "cases": SWEEP_JOB["cases"][:2],
}


def test_a_job_with_a_budget_gives_the_merges_report_with_its_budget(tmp_path: Path) -> None:
    job = tmp_path / "job.json"
    job.write_text(json.dumps(BUDGET_JOB))
    shards = tmp_path / "shards"
    tool("mc-shard", "run", "--job", str(job), "--out", str(shards), "--quiet")
    report = tmp_path / "report"
    console = tool("mc-merge", str(shards), "--out", str(report), *FAST).stdout
    written = (report / "report.json").read_text()
    budget = json.loads(written)["budget"]
    assert [line["quantity"] for line in budget["lines"]] == ["theta_p", "decenter", "despace"], budget
    # In-process and read back, the summary holds the same budget section, to the byte.
    summary = truss_mc.Job.from_file(job).run(threads=2).summary(**settings())
    assert summary.data["budget"] == budget
    assert summary.text == written
    assert console.endswith(f"{summary.answer.text}\nreport: {report / 'report.html'}\n"), console
    assert truss_mc.read_shards(shards).summary(threads=1, **settings()).text == written
