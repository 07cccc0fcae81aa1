#!/usr/bin/env python3
"""opensees_prism.py: solve a truss-mc model's Monte Carlo samples in OpenSeesPy, for
scripts/bench-opensees.sh.

Reads a model file as `truss model prism` writes it (nodes, members, supports, loads,
top surface; units mm, N, MPa), the samples' drawn length errors as `mc-shard inputs`
writes them (CSV, mm), and optionally the shard lines mc-shard wrote for the same samples.
For each sample it solves the static equilibrium in OpenSeesPy and measures the top
surface's distortion angle θ_P; it prints one JSON object: the samples solved, the seconds
they took, wall and CPU (set-up of the model excluded), the CPU time of OpenSees's
`analyze` alone (the solve, without the Python that sets each sample's materials), and, given shard lines, the largest relative
difference |θ_P(OpenSees) − θ_P(mc-shard)| / θ_P(mc-shard).

The OpenSees model, member by member (L_r the nominal distance between the member's
nodes, e its drawn length error, L₀ = natural_length + e its stress-free length):

    element corotTruss (corotational: large displacements, engineering strain
        ε = (L − L_r)/L_r, force N = A·σ along the deformed axis)
    material InitStrainMaterial(ε₀) around Elastic(E', 0, E'_neg), σ = E'·(ε + ε₀)
        ε₀ = (L_r − L₀)/L_r     zero stress at L = L₀: a member too long by e has ε₀ = −e/L_r
        E' = E·L_r/L₀           so that N = E'·A·(L − L₀)/L_r = E·A·(L − L₀)/L₀, mc-shard's
                                 force (crates/truss-core/src/element.rs); with E' = E,
                                 θ_P moves by some 1e-5 of itself, the order of e/L_r
        E'_neg = E' for bars; r·E' for cables (tension only), r the compression ratio

A cable of compression ratio 0 (the model's default, the paper's) is what mc-shard solves
as the limit r → 0, at the working ratio 1e-4 where bars frame the top surface's tilt, as
they do in the rigid prism (crates/truss-core/src/limit.rs); --cable-ratio sets r here
(default 1e-4, the same working ratio). At 0, a cable with no compression stiffness at
all, OpenSees's Newton fails on most samples of the rigid prism (a panel whose bracing is
all slack is a mechanism, its tangent singular), as mc-shard's would: that is why
mc-shard solves the limit at a working ratio.

Per sample only the materials change: the model (nodes, supports, elements, analysis) is
built once, and each sample sets the ε₀, E' and E'_neg of every member whose values
changed (`updateParameter`; the rigid case's diagonals draw no error and keep theirs),
returns the domain to its undeformed start with `reset`, and runs one Newton step of
load control (RCM numbering, banded Cholesky `BandSPD` as mc-shard factorises, no
external load: the initial strains are the load), converged when the norm of the
displacement increment is below --tolerance mm (default 1e-10 mm, against displacements
of about 0.01 mm: the tightest that Newton reaches without round-off stalling some
samples; θ_P then agrees with mc-shard's to about 1e-10). --rebuild builds the whole
model again for each sample instead (`wipe`), a check that updating the parameters does
what a fresh model does.

θ_P is measured as mc-shard measures it (crates/truss-core/src/measure.rs):
n_t = (p₂ − p₁) × (p₃ − p₁), θ_P = atan2(|n_t × n_b|, n_t·n_b), the positions' differences
formed as nominal difference plus displacement difference.

Usage: opensees_prism.py --model MODEL.json --inputs INPUTS.csv [--lines SHARD.jsonl]
                         [--samples N] [--cable-ratio R] [--tolerance MM] [--rebuild]
"""

import argparse
import csv
import json
import math
import sys
import time

import openseespy.opensees as ops

LENGTH_ERROR = "length_error:"


def distance(a, b):
    return math.sqrt(sum((q - p) ** 2 for p, q in zip(a, b)))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def theta_p(x, u, n_b):
    """θ_P [rad] of the surface through nominal positions x and displacements u [mm]."""
    e1 = [(x[1][k] - x[0][k]) + (u[1][k] - u[0][k]) for k in range(3)]
    e2 = [(x[2][k] - x[0][k]) + (u[2][k] - u[0][k]) for k in range(3)]
    n = cross(e1, e2)
    s = cross(n, n_b)
    return math.atan2(math.sqrt(sum(c * c for c in s)), sum(p * q for p, q in zip(n, n_b)))


class Prism:
    """A model file in OpenSeesPy: one node, element and material pair per model item."""

    def __init__(self, model, cable_ratio, tolerance):
        if model.get("joints"):
            sys.exit("opensees_prism: models with joints (backlash) are not supported")
        self.model = model
        self.cable_ratio = cable_ratio
        self.tolerance = tolerance
        self.analyze = 0.0
        self.node_tag = {n["id"]: i + 1 for i, n in enumerate(model["nodes"])}
        self.xyz = {n["id"]: n["xyz"] for n in model["nodes"]}
        self.members = model["members"]
        for m in self.members:
            if m.get("compression_ratio", 0.0) != 0.0 and m["behaviour"] == "cable":
                sys.exit("opensees_prism: member %s: only cables of compression ratio 0 "
                         "(the default) are supported" % m["id"])
        self.member_index = {m["id"]: i for i, m in enumerate(self.members)}
        top = model["top_surface"]
        self.top = [self.node_tag[n] for n in top["nodes"]]
        self.top_xyz = [self.xyz[n] for n in top["nodes"]]
        self.n_b = top.get("reference_normal", [0.0, 0.0, 1.0])
        self.reference = [distance(self.xyz[m["nodes"][0]], self.xyz[m["nodes"][1]])
                          for m in self.members]

    def materials(self, errors):
        """(ε₀, E', E'_neg) of each member for the length errors `errors` [mm]."""
        out = []
        for m, l_r, e in zip(self.members, self.reference, errors):
            l0 = m.get("natural_length", l_r) + e
            modulus = m["youngs_modulus"] * l_r / l0
            negative = modulus if m["behaviour"] == "bar" else self.cable_ratio * modulus
            out.append(((l_r - l0) / l_r, modulus, negative))
        return out

    def build(self, errors):
        """Builds the whole OpenSees domain and analysis for one sample's errors."""
        ops.wipe()
        self.current = self.materials(errors)
        ops.model("basic", "-ndm", 3, "-ndf", 3)
        for n in self.model["nodes"]:
            ops.node(self.node_tag[n["id"]], *n["xyz"])
        for s in self.model.get("supports", []):
            ops.fix(self.node_tag[s["node"]], *[int(c in s["fixed"]) for c in "xyz"])
        for i, (m, (eps0, modulus, negative)) in enumerate(
                zip(self.members, self.current)):
            tag = i + 1
            ops.uniaxialMaterial("Elastic", 100000 + tag, modulus, 0.0, negative)
            ops.uniaxialMaterial("InitStrainMaterial", tag, 100000 + tag, eps0)
            a, b = (self.node_tag[n] for n in m["nodes"])
            ops.element("corotTruss", tag, a, b, m["area"], tag)
        ops.timeSeries("Constant", 1)
        ops.pattern("Plain", 1, 1)
        for load in self.model.get("loads", []):
            ops.load(self.node_tag[load["node"]], *load["force"])
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("BandSPD")
        ops.test("NormDispIncr", self.tolerance, 50)
        ops.algorithm("Newton")
        ops.integrator("LoadControl", 1.0)
        ops.analysis("Static")
        # Parameters addressing each element's material, so a sample can set them.
        for i in range(len(self.members)):
            tag = i + 1
            ops.parameter(3 * tag, "element", tag, "material", "epsInit")
            ops.parameter(3 * tag + 1, "element", tag, "material", "E")
            ops.parameter(3 * tag + 2, "element", tag, "material", "Eneg")

    def update(self, errors):
        """Sets one sample's materials in the built model and returns it to its start;
        a member whose values are those of the previous sample (a member without a drawn
        error, such as the rigid case's diagonals) is left as it is."""
        ops.reset()
        materials = self.materials(errors)
        for i, (now, before) in enumerate(zip(materials, self.current)):
            if now != before:
                tag = i + 1
                ops.updateParameter(3 * tag, now[0])
                ops.updateParameter(3 * tag + 1, now[1])
                ops.updateParameter(3 * tag + 2, now[2])
        self.current = materials

    def solve(self):
        """Solves the current sample: (θ_P [rad], or None if Newton did not converge;
        Newton iterations). Adds the CPU time of OpenSees's `analyze` to `self.analyze`."""
        start = time.process_time()
        status = ops.analyze(1)
        self.analyze += time.process_time() - start
        if status != 0:
            return None, ops.testIter()
        u = [ops.nodeDisp(t) for t in self.top]
        return theta_p(self.top_xyz, u, self.n_b), ops.testIter()


def read_inputs(path, members, count):
    """The first `count` samples' (index, length errors in the model's member order)."""
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = next(rows)
        columns = {name[len(LENGTH_ERROR):]: k for k, name in enumerate(header)
                   if name.startswith(LENGTH_ERROR)}
        missing = [m["id"] for m in members if m["id"] not in columns]
        if missing:
            sys.exit("opensees_prism: %s has no length error for member %s" % (path, missing[0]))
        samples = []
        for row in rows:
            if len(samples) == count:
                break
            samples.append((int(row[0]), [float(row[columns[m["id"]]]) for m in members]))
    return samples


def read_lines(path):
    """θ_P of each sample line of a shard, by global index."""
    theta = {}
    with open(path) as f:
        for line in f:
            record = json.loads(line)
            if record.get("record") == "sample" and record.get("status") == "converged":
                theta[record["index"]] = record["theta_p"]
    return theta


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", required=True)
    parser.add_argument("--inputs", required=True)
    parser.add_argument("--lines", help="mc-shard's shard lines of the same samples")
    parser.add_argument("--samples", type=int, default=500)
    parser.add_argument("--cable-ratio", type=float, default=1e-4)
    parser.add_argument("--tolerance", type=float, default=1e-10)
    parser.add_argument("--rebuild", action="store_true")
    args = parser.parse_args()

    with open(args.model) as f:
        prism = Prism(json.load(f), args.cable_ratio, args.tolerance)
    samples = read_inputs(args.inputs, prism.members, args.samples)
    prism.build(samples[0][1])

    results = []
    newton = 0
    prism.analyze = 0.0
    start = time.perf_counter()
    cpu = time.process_time()
    for index, errors in samples:
        if args.rebuild:
            prism.build(errors)
        else:
            prism.update(errors)
        theta, iterations = prism.solve()
        results.append((index, theta))
        newton += iterations
    seconds = time.perf_counter() - start
    cpu = time.process_time() - cpu

    summary = {"samples": len(results), "seconds": seconds, "cpu_seconds": cpu,
               "analyze_cpu_seconds": prism.analyze,
               "failed": sum(t is None for _, t in results),
               "iterations": newton / len(results),
               "per_sample": "rebuilt" if args.rebuild else "materials updated"}
    if args.lines:
        ours = read_lines(args.lines)
        worst = (0.0, None)
        for index, theta in results:
            if theta is None or index not in ours:
                continue
            diff = abs(theta - ours[index]) / ours[index]
            worst = max(worst, (diff, index), key=lambda w: w[0])
        summary["compared"] = sum(t is not None and i in ours for i, t in results)
        summary["max_relative_difference"] = worst[0]
        summary["worst_index"] = worst[1]
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
