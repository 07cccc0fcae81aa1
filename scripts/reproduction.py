#!/usr/bin/env python3
"""Writes REPRODUCTION.md (to stdout) from the merged reports of the paper's studies.

Usage: scripts/reproduction.py RUNS_DIR   (RUNS_DIR/paper-3.1/report/report.json, …)

Every number in the tables comes from a report.json written by mc-merge; the paper's numbers
are quoted from the paper. The explanations are ours, and say what each comparison rests on.
"""

import datetime
import json
import math
import pathlib
import subprocess
import sys

L = 380.0  # batten length, mm
RAYLEIGH_95 = math.sqrt(-2.0 * math.log(0.05))  # eq. 28 multiplier, 2.4477


def load(runs, study):
    path = pathlib.Path(runs) / f"paper-{study}" / "report" / "report.json"
    with open(path) as f:
        return json.load(f)


def case(report, name):
    return next(c for c in report["cases"] if c["name"] == name)


def holding_median(c):
    """The median holding force of a case [N], or — where its samples do not record it."""
    h = c.get("holding_force", {})
    values = [p["value"] for p in h.get("percentiles", []) if p["percentile"] == 50 and p["value"] is not None]
    return f"{values[0]:.2e}" if h.get("recorded") and values else "—"


def held_loosely(c):
    """Samples held by less than 1 µN, as a percentage of all and of those above θ_P95."""
    h = c.get("holding_force", {})
    if not h.get("recorded"):
        return "—"
    tail = f"{100 * h['tail_loose'] / h['tail_recorded']:.1f} %" if h["tail_recorded"] else "—"
    return f"{100 * h['loose'] / h['recorded']:.1f} % / {tail}"


def p95(c):
    return next(p for p in c["percentiles"] if p["percentile"] == 95.0)


def interval(fig, key="bca"):
    i = fig[key]
    return fig["value"], i["lower"], i["upper"]


def e(x, digits=3):
    return f"{x:.{digits}e}"


def failed(report):
    return sum(c["failed"]["count"] for c in report["cases"])


def mean_iterations(runs, study, names):
    """Mean Newton iterations per converged sample of each named case, read from the shards."""
    sums = {n: [0, 0] for n in names}
    for path in sorted((pathlib.Path(runs) / f"paper-{study}").glob("shard-*.jsonl")):
        with open(path) as f:
            for line in f:
                if '"record":"sample"' not in line:
                    continue
                r = json.loads(line)
                if r["case"] in sums and r["status"] == "converged":
                    sums[r["case"]][0] += r["iterations"]
                    sums[r["case"]][1] += 1
    return {n: s / c for n, (s, c) in sums.items()}


def commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True).stdout.strip()
    except Exception:
        return "unknown"


def default_backlash_series(r):
    """The σ series of the backlash cases at the default regularisation (none)."""
    return next(s for s in r["sweep"]["sigma_series"]
                if "backlash=1" in s["name"] and "joint_compression_ratio=0," in s["name"] + ","
                and "cable_compression_ratio" not in s["name"])


def floating(c):
    """The case's fraction of floating samples, in percent, with its interval."""
    f = c["floating"]["fraction"]
    return f"{f['value'] * 100:.1f} % [{f['lower'] * 100:.1f}, {f['upper'] * 100:.1f}]"


def sigma_t(c):
    """The case's Rayleigh scale σ_t."""
    return c["rayleigh"]["sigma_t"]["value"] if isinstance(c["rayleigh"]["sigma_t"], dict) else c["rayleigh"]["sigma_t"]


def backlash_section(runs, w):
    """§4.2.3 (Fig. 16): θ_P95 with and without backlash against σ, and the regularisation."""
    r = load(runs, "4.2.3")
    sigmas = [0.0067, 0.013, 0.017, 0.033, 0.05, 0.067]
    series = {s["name"]: s for s in r["sweep"]["sigma_series"]}
    with_bl = default_backlash_series(r)
    rigid = next(s for n, s in series.items() if "backlash" not in n)
    n_bl = case(r, "backlash-sigma-0.0067")["n"]
    w("## Backlash (§4, Figs. 12–16)\n")
    w("Each longeron end sits in its own hole on its batten's shaft (two joints at every node between stages, 30 in "
      "the 5-stage truss). A loose pin carries no force; a pin that carries a force bears on its hole's edge along "
      "that force, penetrating it by F/k_t (k_t = 1e5 × the longeron's E·A/L). The hole nodes are eliminated exactly: "
      "a longeron with its two joints is a bar with a dead band ±(g₁ + g₂), solved as a tension-only half in parallel "
      "with a compression-only half by the same active-set steps that find the slack cables, with no regularisation "
      "by default (see `crates/truss-core/src/joint.rs`). The paper's demonstrations are tests in "
      "`crates/truss-core/tests/it/backlash.rs`: the 30 mm panel of Figs. 12/13 (diagonals 445.1 mm) shortens to L − 2g "
      "with every shaft on its hole's edge along the longeron; the 1-stage truss of Figs. 14/15 does not twist and its "
      "shafts rest on the hole edges — with diagonals of 490 mm, because the paper's 428.1 mm, with Table 1's sections, "
      "pretension the pin-jointed prism past its twisting limit. A third, by hand: the 5-stage truss with every "
      "diagonal shortened by 0.05 mm drops by the stacked clearances less the elastic shortening the slackened "
      "diagonals no longer cause (0.044214 mm solved against 0.044215 mm by hand for g = 0.005 mm).\n")
    w(f"Fig. 16, from `jobs/paper-4.2.3.json`: 5 stages, battens and longerons N(0, σ²), diagonals U[−3σ, 0], "
      f"clearances U[0.004, 0.017] mm per joint and sample, {n_bl:,} samples per point (the paper used 1,000).\n")
    w("| σ [mm] | θ_P95 with backlash [95 % CI] | θ_P95 without [95 % CI] | ratio | samples with a loose joint | floating | holding force, median [N] | held by < 1 µN: all / above θ_P95 |")
    w("|---|---|---|---|---|---|---|---|")
    for sg in sigmas:
        b, g = case(r, f"backlash-sigma-{sg}"), case(r, f"rigid-sigma-{sg}")
        vb, lb, hb = interval(p95(b))
        vr, lr, hr = interval(p95(g))
        loose = b["loose_joints"]["fraction"]["value"]
        w(f"| {sg} | {e(vb)} [{e(lb)}, {e(hb)}] | {e(vr)} [{e(lr)}, {e(hr)}] | {vb / vr:.3f} | {loose * 100:.1f} % | {floating(b)} | {holding_median(b)} | {held_loosely(b)} |")
    w("")
    w("The holding force (`crates/truss-core/src/solver/holding.rs`) is the largest force on one node of the top "
      "surface that, to first order, moves θ_P by at most 1 % and lets no bearing cable or joint go. A sample held "
      "by less than 1 µN sits wherever friction, the diagonals' bending stiffness or the assembly left it; where "
      "such samples make up much of the tail above θ_P95, θ_P95 is the model's answer for frictionless joints, not a "
      "prediction of a built truss. The test `the_holding_force_bounds_a_load_that_moves_theta_by_one_percent` "
      "re-solves 60 Fig. 16 samples with loads on the top node it names: below the holding force θ_P moves by less "
      "than 1 %, above it by more, or the member it names lets go.\n")
    ab = with_bl["allowable_sigma"]["through_origin"]
    ar = rigid["allowable_sigma"]["through_origin"]
    w("| allowable σ for θ_P95 ≤ 20\" | paper | ours [95 % interval] |")
    w("|---|---|---|")
    w(f"| with backlash | 7.18e-3 mm | none: θ_P95 is {e(p95(case(r, 'backlash-sigma-0.0067'))['value'])} rad "
      f"({p95(case(r, 'backlash-sigma-0.0067'))['value'] * 206265:.1f}\") already at σ = 0.0067 mm, and does not "
      f"fall to zero with σ (a line through the origin would say {e(ab['value'])} mm) |")
    w(f"| without backlash (same diagonal errors) | 6.30e-3 mm | {e(ar['value'])} [{e(ar['lower'])}, {e(ar['upper'])}] mm |")
    w("")
    w("Regularisation: how much the answer depends on a stiffness k_c = ratio × k_t given to loose joints "
      "(2,000 samples each; the default is none):\n")
    w("| k_c / k_t | σ = 0.0067: θ_P95 [95 % CI] | σ = 0.0067: σ_t | σ = 0.033: θ_P95 [95 % CI] | σ = 0.033: σ_t | loose-joint samples (σ = 0.033) |")
    w("|---|---|---|---|---|---|")
    for ratio, prefix in [("0 (default, 10,000 samples)", "backlash-sigma-"), ("1e-15", "backlash-ratio-1e-15-sigma-"),
                          ("1e-12", "backlash-ratio-1e-12-sigma-"), ("1e-9", "backlash-ratio-1e-09-sigma-"),
                          ("1e-5 (an earlier default)", "backlash-ratio-1e-05-sigma-")]:
        lo_c, hi_c = case(r, f"{prefix}0.0067"), case(r, f"{prefix}0.033")
        v1, l1, h1 = interval(p95(lo_c))
        v2, l2, h2 = interval(p95(hi_c))
        w(f"| {ratio} | {e(v1)} [{e(l1)}, {e(h1)}] | {e(sigma_t(lo_c))} | {e(v2)} [{e(l2)}, {e(h2)}] | {e(sigma_t(hi_c))} | {hi_c['loose_joints']['fraction']['value'] * 100:.1f} % |")
    w("")
    w("The diagonals' compression ratio r: their stiffness when slack over their stiffness in tension. The default "
      "is the paper's zero, solved as the limit r → 0 (`crates/truss-core/src/limit.rs`), against r = 1e-10, near "
      "the solver's force resolution (a reference for the limit), and 1e-4, the regularisation that was the "
      "default before (10,000 samples each, drawn independently):\n")
    w("| σ [mm] | θ_P95, default [95 % CI] | θ_P95, r = 1e-10 [95 % CI] | default / 1e-10 | θ_P95, r = 1e-4 [95 % CI] | 1e-4 / 1e-10 | σ_t, default / 1e-10 / 1e-4 | loose joint, default / 1e-10 / 1e-4 | floating, default | failed, 1e-10 |")
    w("|---|---|---|---|---|---|---|---|---|---|")
    for sg in ["0.0067", "0.013"]:
        d = case(r, f"backlash-sigma-{sg}")
        z = case(r, f"backlash-diagonal-ratio-1e-10-sigma-{sg}")
        o = case(r, f"backlash-diagonal-ratio-1e-04-sigma-{sg}")
        vd, ld, hd = interval(p95(d))
        vz, lz, hz = interval(p95(z))
        vo, lo_, ho = interval(p95(o))
        loose = lambda c: f"{c['loose_joints']['fraction']['value'] * 100:.1f} %"
        w(f"| {sg} | {e(vd)} [{e(ld)}, {e(hd)}] | {e(vz)} [{e(lz)}, {e(hz)}] | {vd / vz:.3f} | "
          f"{e(vo)} [{e(lo_)}, {e(ho)}] | {vo / vz:.3f} | {e(sigma_t(d))} / {e(sigma_t(z))} / {e(sigma_t(o))} | "
          f"{loose(d)} / {loose(z)} / {loose(o)} | {floating(d)} | {z['failed']['count']} |")
    w("")
    w("Diagonals shortened by less, where some joints carry almost nothing (2,000 samples each):\n")
    w("| diagonals | σ = 0.0067: θ_P95 [95 % CI] | σ = 0.033: θ_P95 [95 % CI] | failed |")
    w("|---|---|---|---|")
    for label, name in [("U[−3σ, 0] (Fig. 16)", "backlash-sigma-"), ("U[−σ, 0]", "backlash-light-sigma-"),
                        ("U[−0.2σ, 0]", "backlash-slight-sigma-")]:
        lo_c, hi_c = case(r, f"{name}0.0067"), case(r, f"{name}0.033")
        v1, l1, h1 = interval(p95(lo_c))
        v2, l2, h2 = interval(p95(hi_c))
        w(f"| {label} | {e(v1)} [{e(l1)}, {e(h1)}] | {e(v2)} [{e(l2)}, {e(h2)}] | {lo_c['failed']['count'] + hi_c['failed']['count']} |")
    w("")
    at_defaults = sum(c["failed"]["count"] for c in r["cases"] if "ratio" not in c["name"])
    others = [(c["name"], c["failed"]["count"]) for c in r["cases"] if "ratio" in c["name"] and c["failed"]["count"]]
    w(f"Failed samples: {at_defaults} of the {sum(c['expected'] for c in r['cases'] if 'ratio' not in c['name'])} "
      "at the defaults; in the cases with a ratio set: "
      + (", ".join(f"{k} in `{n}`" for n, k in others) if others else "none")
      + " (left out of those cases' figures).\n")
    w("What this says, against the paper's two conclusions.\n")
    w("- *Backlash dominates at small σ*: agreed, and more strongly than the paper's Fig. 16. At σ = 0.0067 mm "
      "backlash raises θ_P95 by about half (ratio column), because the diagonals' pretension (a shortening of at "
      "most 3σ = 0.02 mm, a mean of 0.01 mm) is too small to take up clearances of 2 × 0.004–0.017 mm per longeron: "
      "a stage shortens by its longerons' free play only until its diagonals go slack, so in almost every sample "
      "some longerons float in their holes (the loose-joint column) and their stages are held by what is left. "
      "As σ, and with it the pretension, grows, the joints are taken up "
      f"({case(r, 'backlash-sigma-0.033')['loose_joints']['fraction']['value'] * 100:.1f} % of samples have a loose "
      f"joint at σ = 0.033, {case(r, 'backlash-sigma-0.067')['loose_joints']['fraction']['value'] * 100:.1f} % at "
      "0.067) and the ratio goes to 1.\n")
    w("- *Backlash lowers θ_P95 at large σ, by relieving internal forces*: not reproduced. At σ = 0.05 and 0.067 mm the "
      "ratio is 1.00 within its intervals. Our model does let a loaded shaft move within its hole, but a loaded "
      "shaft bears on its edge: the clearance shifts a longeron's effective length by a constant (−2g in "
      "compression) and leaves its stiffness as it was, so it cannot relieve the forces that the length errors "
      "cause once the joints bear. We do not know what in the paper's model relieved them; its regularisation "
      "(a centring stiffness of 1e-5 × k_t, which our earlier model used) changes θ_P95 at σ = 0.033 by less "
      "than its interval (regularisation table).\n")
    w("- *The allowable σ with backlash* is not in the studied range at the paper's clearances: θ_P95 is already "
      "twice the 20\" target at the smallest σ, and less diagonal pretension makes it larger, not smaller (the "
      "U[−σ, 0] and U[−0.2σ, 0] rows), so θ_P95 does not fall in proportion to σ and a line through the origin "
      "is the wrong model. We did not run σ below 0.0067 mm. What the numbers say to an engineer: at these "
      "clearances the joints, not the length tolerance, set the pointing error; smaller clearances or more "
      "pretension come first.\n")
    w("- *The joints' regularisation*: none is needed, and the default is none. The test "
      "`the_answer_does_not_depend_on_the_regularisation` checks θ_P95, σ_t and the mean top position to 1 % "
      "between a loose-joint stiffness of 1e-18 × k_t, 1e-21 × k_t and none. Larger ones are not harmless: at the "
      "limit a floating stage's slack diagonals carry exactly nothing, so a loose longeron's regularisation is the "
      "only stiffness that holds it and picks its position: at 1e-15 (3e-7 N/mm) θ_P95 moves by 8 % in that test; "
      "at 1e-12 (3e-4 N/mm) and 1e-9 (0.3 N/mm) it holds the stages (the table's rows, solved with them), and at "
      "1e-5 loose joints are centred and backlash vanishes.\n")
    lo_d, lo_z = case(r, "backlash-sigma-0.0067"), case(r, "backlash-diagonal-ratio-1e-10-sigma-0.0067")
    lo_o = case(r, "backlash-diagonal-ratio-1e-04-sigma-0.0067")
    its = mean_iterations(runs, "4.2.3", [lo_d["name"], lo_z["name"], lo_o["name"]])
    w("- *The diagonals carry nothing when slack* (the paper's Table 1), and that is the default: it is solved as the "
      "limit r → 0 of their compression ratio, at the limit itself: one-sided members solved as contact, by "
      "continuation from r = 1e-5 to an exact solve at r = 0 (`crates/truss-core/src/solver/limit/`). Against an "
      "independent arbitrary-precision reference (`scripts/limit-reference.sh`, continuation to r = 1e-30), the "
      "θ_P of 200 Fig. 16 samples agree within 7.4e-5, 193 within 1e-6 (`crates/mc-shard/tests/it/limit_reference.rs`; "
      "the former working ratio, 1e-7, was 87 % off in one sample and 2.7 % in another). Where a stage's longerons "
      "float in their holes, it is held only by what pretension is left and by its slack diagonals' r × 404 N/mm, "
      "so any working ratio matters there: at the earlier "
      f"default r = 1e-4, θ_P95 at σ = 0.0067 mm is {100 * (p95(lo_o)['value'] / p95(lo_z)['value'] - 1):+.1f} % "
      "off the reference r = 1e-10 (table above), beyond both intervals, and more samples have a loose joint: the "
      "regularisation, not the model, held those joints off their edges. The default is within "
      f"{100 * abs(p95(lo_d)['value'] / p95(lo_z)['value'] - 1):.1f} % of the reference. The slow tests in "
      "`crates/truss-core/tests/it/backlash.rs` hold it there on the same draws: "
      "`the_default_holds_the_fig16_case_at_its_limit` (1,500 samples: θ_P95 within 1 % of r = 1e-10 and the median "
      "sample within 0.1 %) and `the_default_is_the_diagonals_limit_and_1e4_is_not` (θ_P95, σ_t and the mean top "
      "position within 1 % between the default, 1e-8 and 1e-9). Models whose bars frame the top's tilt (the rigid "
      "prism) are solved at r = 1e-4: there a slack panel's racking moves the top nodes sideways, not up, and θ_P "
      "is the limit's to 2e-4 of its median, sample by sample (`crates/truss-core/tests/it/limit.rs`). Solves at "
      f"the limit cost iterations: at σ = 0.0067 mm {its[lo_d['name']]:.1f} on average with backlash at the "
      f"default, against {its[lo_o['name']]:.1f} at 1e-4 and {its[lo_z['name']]:.1f} at 1e-10 (read from the "
      "shards).\n")
    w("- *Floating stages*: in the limit, a stage whose longerons are loose and whose diagonals are slack is held by "
      "nothing (the tangent of the members that bear is not positive definite) and sits wherever friction, the "
      "diagonals' bending stiffness or the assembly would leave it; the model picks the limit's position, and any "
      "force moves it until its joints come into contact: 1 µN on a top node moves a floating sample's θ_P by a "
      "median of 34 % and a sample not floating's by at most 6e-5 of itself "
      "(`a_floating_sample_is_moved_by_a_micronewton_and_a_held_one_is_not`, in "
      "`crates/truss-core/tests/it/limit.rs`). Each sample line "
      "says whether it floats, and the merge reports the fraction per case (the floating column). Where it exceeds "
      "the 5 % tail that θ_P95 reads (here at σ = "
      + ", ".join(f"{sg}" for sg in sigmas if case(r, f"backlash-sigma-{sg}")["floating"]["fraction"]["value"] > 0.05)
      + " mm), θ_P's upper percentiles rest on effects the model leaves out, and the report says so: more "
      "diagonal pretension or smaller clearances frame the stages.\n")


def tolerance_section(runs, w):
    """§3.1's single allowable σ against the per-group allocation of `truss tolerance`."""
    path = pathlib.Path(runs) / "tolerance-3.1" / "tolerance.json"
    if not path.exists():
        w(f"## Tolerance allocation for 20\" (§3.1)\n\n`{path}` is missing: run `scripts/reproduce-paper.sh`.\n")
        return
    with open(path) as f:
        t = json.load(f)
    g = t["groups"]
    b, lo = g["batten"], g["longeron"]
    n_b, n_l = b["members"], lo["members"]
    paper = 6.30e-3
    cost = lambda sb, sl: n_b / sb + n_l / sl
    c_paper, c_uni, c_alloc = cost(paper, paper), t["uniform_cost"], t["cost"]
    v, u, i = t["verified"], t["uniform_verified"], t["input"]
    arc = lambda x: x * 206264.8
    w("## Tolerance allocation for 20\" (§3.1): one σ for all, or one per group\n")
    w(f"`truss tolerance --job jobs/paper-3.1.json --case sigma-0.0063 --target-arcsec 20` (read from `{path}`): "
      f"the sensitivity from {i['samples']:,} samples at σ = 6.30e-3 mm, each allocation verified with "
      f"{v['samples']:,} samples (θ_P95 with its 95 % BCa interval; the target must hold at the upper end). "
      "Cost = Σ n/σ over the members, every member weighted alike.\n")
    w("| tolerance | batten σ [mm] | longeron σ [mm] | θ_P95 [95 % interval] | cost / uniform |")
    w("|---|---|---|---|---|")
    w(f"| the paper's single σ (§3.1) | {e(paper)} | {e(paper)} | {e(i['theta_p'])} [{e(i['interval'][0])}, {e(i['interval'][1])}] rad ({arc(i['theta_p']):.1f}\"): over the target | {c_paper / c_uni:.3f} |")
    w(f"| our single σ meeting 20\" | {e(t['uniform_sigma'])} | {e(t['uniform_sigma'])} | {e(u['theta_p'])} [{e(u['interval'][0])}, {e(u['interval'][1])}] rad ({arc(u['theta_p']):.2f}\") | 1 |")
    w(f"| **per group, allocated** | **{e(b['sigma'])}** | **{e(lo['sigma'])}** | {e(v['theta_p'])} [{e(v['interval'][0])}, {e(v['interval'][1])}] rad ({arc(v['theta_p']):.2f}\") | **{t['cost_ratio']:.3f}** |")
    w("")
    w(f"The longerons carry {lo['share']:.4f} [{lo['share_interval'][0]:.4f}, {lo['share_interval'][1]:.4f}] of the variance of "
      f"tan θ_x and tan θ_y, the battens {b['share']:.4f} [{b['share_interval'][0]:.4f}, {b['share_interval'][1]:.4f}] "
      f"(linear model; {t['nonlinear_share']:.4f} unexplained), so the battens can be made "
      f"{b['sigma'] / lo['sigma']:.1f}× looser than the longerons (σ ∝ (n/S)^(1/3)), and the longerons must be held to "
      f"{lo['sigma'] / t['uniform_sigma']:.3f}× the common σ. Meeting 20\" costs {100 * (1 - t['cost_ratio']):.0f} % less "
      f"than with one common σ, and {100 * (1 - c_alloc / c_paper):.0f} % less than the paper's single σ of 6.30e-3 mm, "
      "which in our model does not meet 20\" (see above). The paper's own conclusion, one σ for battens and "
      "longerons, over-specifies the battens whichever scale is right: the share is a ratio, and the paper "
      "too finds the top heights set by the longerons.\n")


def main(runs):
    r31, r33, r34 = load(runs, "3.1"), load(runs, "3.3"), load(runs, "3.4")
    c63 = case(r31, "sigma-0.0063")
    v, lo, hi = interval(p95(c63))
    st = c63["rayleigh"]["sigma_t"]["value"]
    st_lo, st_hi = c63["rayleigh"]["sigma_t"]["lower"], c63["rayleigh"]["sigma_t"]["upper"]
    series = r31["sweep"]["sigma_series"][0]
    slope = series["through_origin"]["slope"]
    r2 = series["through_origin"]["r_squared"]["value"]
    allow = series["allowable_sigma"]["through_origin"]
    kin5 = math.sqrt(2 * 5) * 0.0063 / L
    gof = {c["name"]: c["gof"] for c in r33["cases"]}
    gof5 = c63["gof"]
    stages = r34["sweep"]["stages_series"][0]
    out = []
    w = out.append
    w("# Reproducing the paper\n")
    w(f"Generated by `scripts/reproduce-paper.sh` on {datetime.date.today()} at commit `{commit()}` from "
      "`jobs/paper-3.1.json`, `jobs/paper-3.3.json`, `jobs/paper-3.4.json` and `jobs/paper-4.2.3.json`; every figure of ours is read "
      f"from the merged `report.json` under `{runs}/paper-*/report/` (intervals: 95 % BCa bootstrap, "
      "B = 2000, unless said otherwise). The paper is Kobayashi et al., Trans. JSASS 2021.\n")
    w("## Summary\n")
    w("| quantity | paper | ours [95 % interval] | agreement |")
    w("|---|---|---|---|")
    w(f"| θ_P95 at σ = 6.30e-3 mm (§3.1, Fig. 4) | 9.69e-5 rad (20.0\") | {e(v)} [{e(lo)}, {e(hi)}] rad ({v * 206264.8:.1f}\") | **differs**: {v / 9.69e-5:.2f}× the paper |")
    w(f"| σ_t at σ = 6.30e-3 mm (§3.2, Fig. 6) | 3.96e-5 | {e(st)} [{e(st_lo)}, {e(st_hi)}] (ML, zero mean, pooled tan θ_x, tan θ_y) | **differs**: {st / 3.96e-5:.2f}× |")
    w(f"| θ_P95 linear in σ (§3.1, Fig. 3) | a straight line through all points | slope {e(slope['value'], 4)} [{e(slope['lower'], 4)}, {e(slope['upper'], 4)}] rad/mm through the origin, R² = {r2:.5f} over σ = 0.0033 … 0.067 mm | agrees |")
    w(f"| allowable σ for θ_P95 ≤ 20\" (§3.1) | 6.30e-3 mm | {e(allow['value'])} [{e(allow['lower'])}, {e(allow['upper'])}] mm | **differs** (follows from the slope) |")
    w(f"| Rayleigh law, 5-stage normal (§3.2, Fig. 7) | holds | {gof5['verdict']} (KS p = {gof5['ks']['p_value']:.2f}, AD p = {gof5['ad']['p_value']:.2f}); Rayleigh θ_P95 within {abs(gof5['effect']['relative_difference']['value']) * 100:.1f} % of the empirical one | agrees |")
    for name, paper in [("1-stage-uniform", "rejected"), ("30-stage-uniform", "holds"), ("1-stage-normal", "holds (Fig. 8)")]:
        g = gof[name]
        agrees = "agrees" if (g["verdict"] == "holds") == paper.startswith("holds") else "**differs**"
        w(f"| Rayleigh law, {name.replace('-', ' ')} (§3.3, Fig. 8) | {paper} | {g['verdict']} (KS p = {g['ks']['p_value']:.3f}, AD p = {g['ad']['p_value']:.3f}) | {agrees} |")
    peak = int(stages["peak_stages"])
    w(f"| θ_P95 against the number of stages (§3.4, Fig. 9) | peaks at 4 stages, then falls and levels off | grows about as √N; largest at {peak} stages | **differs** |")
    r423 = load(runs, "4.2.3")
    b0 = p95(case(r423, "backlash-sigma-0.0067"))["value"]
    w(f"| allowable σ with backlash (§4.2.3, Fig. 16) | 7.18e-3 mm (6.30e-3 without) | none: θ_P95 = {b0 * 206265:.1f}\" already at σ = 0.0067 mm | **differs**: backlash raises θ_P95 at small σ (see below) |")
    w("")
    w(f"Failed samples: {failed(r31)} of {r31['job_samples']} (§3.1), {failed(r33)} of {r33['job_samples']} (§3.3), "
      f"{failed(r34)} of {r34['job_samples']} (§3.4), {failed(r423)} of {r423['job_samples']} (§4.2.3).\n")

    w("## The independent check: top-node heights as sums of longeron errors\n")
    w("If the stages were rigid apart from their longerons, each top node's height would be the sum of the N "
      "longeron errors below it, so z_i ~ N(0, Nσ²) and, by the paper's eqs. 17–20, tan θ_x and tan θ_y ~ "
      "N(0, σ_t²) with σ_t = √(2N)·σ/l, and θ_P95 = σ_t·√(−2 ln 0.05) (eq. 28). This estimate owes nothing to "
      "our solver. For N = 5 and σ = 6.30e-3 mm:\n")
    w("| | σ_t | θ_P95 | ratio to the estimate |")
    w("|---|---|---|---|")
    w(f"| estimate √(2N)·σ/l | {e(kin5)} | {e(kin5 * RAYLEIGH_95)} | 1 |")
    w(f"| ours (nonlinear FE, 50,000 samples) | {e(st)} | {e(v)} | {st / kin5:.3f} |")
    w(f"| the paper | 3.96e-5 | 9.69e-5 | {3.96e-5 / kin5:.3f} |")
    w("")
    w("Our solver sits 2 % below the estimate, as it should: the longerons are elastic and the "
      "stage's bracing takes a little of each error (the one-longeron test of truss-core measures 3 % for a single "
      "0.01 mm longeron). The battens add almost nothing: with errors on battens alone θ_P95 is about 4 % of that "
      "with both (their changes of length move the triangle in its plane, not its height). Whether the "
      "diagonals are tension-only or ordinary bars moves θ_P95 by 1.5 %, and the cables' compression "
      "stiffness ratio from 1e-7 to 1e-3 not at all (tested in truss-core). The paper's σ_t is "
      f"{3.96e-5 / kin5:.2f} of the estimate: its heights vary as if about {2 * (3.96e-5 / kin5) ** 2 * 5 / 2:.1f} longeron "
      "errors accumulated instead of 5.\n")

    w("## Why we differ from the paper\n")
    w("We have not tuned the model to the paper's numbers, and we do not know the paper's model beyond what it "
      "prints. What we can say:\n")
    w("- Our figures follow from the geometry the paper describes (Fig. 1, Table 1: 380 mm battens and "
      "longerons, crossed tension-only diagonals of 537.4 mm, the bottom fixed, θ_P between the top triangle's "
      "normal and the bottom's, eq. 2) and agree with the kinematic estimate above, which the paper's own "
      "eqs. 17–20 imply once σ_z² = Nσ² (the paper's statement that each top height is \"nearly equal to the "
      "summation of the member length uncertainties of the longerons under the nodes\").")
    w("- The solver is verified independently of its own output: hand solutions (bars and cables in series), "
      "finite-difference gradient and tangent, rigid-rotation invariance to 1e-9, positive homogeneity to 1e-7, "
      "the one-longeron hand estimate, and the sweep above against √(2N)·σ/l (see `crates/truss-core/tests` and "
      "`tests/`).")
    w("- A σ_t of 0.755 of the estimate, and a θ_P95 that stops growing after 4 stages, would need a mechanism "
      "that makes a stage's tilt depend on fewer than all the longeron errors below it, or that cancels them "
      "between stages. In a stack of statically determinate stages (each braced by one taut diagonal per face, "
      "as ours are) the stages' rotations add up like a random walk, which gives √N. We do not see such a "
      "mechanism in the paper's description; candidates we cannot check are a different error model in the "
      "paper's Monte Carlo (for example errors drawn for fewer members, or correlated between stages), a "
      "different boundary condition, or a solver that did not reach equilibrium in the stages whose diagonals "
      "go slack (with zero compression stiffness those stages are mechanisms, Table 1).")
    w("- The relations the paper derives from its simulations do hold in ours: θ_P95 is linear in σ, θ_P is "
      "Rayleigh distributed with σ_t from tan θ_x and tan θ_y (eq. 28 gives the 95th percentile to within "
      f"{abs(gof5['effect']['relative_difference']['value']) * 100:.1f} %), the 1-stage truss with uniform errors is not "
      "Rayleigh and the 30-stage one is. Only the scale differs, so the allowable σ differs by the same factor: "
      f"**{e(allow['value'])} mm for 20 arcsec at the 95th percentile, not 6.30e-3 mm**.\n")

    w("## Stage count (§3.4, Fig. 9): 3σ = 0.2 mm, 5,000 samples per stage count\n")
    w("| stages | θ_P95 [rad] | normalised to 1 stage [95 % interval] | √N |")
    w("|---|---|---|---|")
    by_stage = {int(p["stages"]): p for p in stages["points"]}
    for n in sorted(by_stage):
        p = by_stage[n]
        value = p["value"]["value"]
        norm = p["normalised"]
        w(f"| {n} | {e(value)} | {norm['value']:.3f} [{norm['lower']:.3f}, {norm['upper']:.3f}] | {math.sqrt(n):.3f} |")
    w("")
    w("The paper's Fig. 9 peaks at 4 stages and then levels off; ours grows with the stage count, a little "
      "below √N at many stages (the taut diagonals of each stage resist part of each longeron's error). Every "
      "stage count's θ_P still follows the Rayleigh law (the paper's Fig. 10), with σ_t growing as √N. For the "
      "design conclusion the paper draws (\"a 5-stage truss is sufficient for investigation\"), our results say "
      "the opposite: a longer truss tilts more, and each design length must be simulated.\n")

    backlash_section(runs, w)

    tolerance_section(runs, w)

    w("## Plots\n")
    w(f"`{runs}/paper-3.1/report/` holds θ_P95 against σ with the fitted line and the 20\" target (Fig. 3), "
      "the θ_P histogram with the fitted Rayleigh density for each σ (Figs. 4, 7) and the tan θ_x, tan θ_y "
      f"histograms with their normal densities (Fig. 6); `{runs}/paper-3.3/report/` the three histograms of "
      f"Fig. 8; `{runs}/paper-3.4/report/` the normalised stage curve (Fig. 9); `{runs}/paper-4.2.3/report/sigma-sweep.svg` "
      "θ_P95 against σ with and without backlash and for each regularisation (Fig. 16).\n")
    sys.stdout.write("\n".join(out))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "runs")
