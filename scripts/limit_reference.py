#!/usr/bin/env python3
"""limit_reference.py: an independent high-precision reference for the limit r -> 0 of theta_P.

What it computes
----------------
For each Monte Carlo sample (a row of `mc-shard inputs`: every member's length error and,
for a model with pin joints, every joint's clearance) of a truss model file (`truss model
...`), the static equilibrium of the truss in arbitrary-precision arithmetic (python-flint's
arb, 96 digits (327 bits) by default, --dps; mpmath is not used) for a cable compression-stiffness
ratio r = 1e-4, 1e-5, ..., 1e-30 (continuation, each warm-started from the last), the
distortion angle theta_P at each r, whether theta_P has settled (the limit r -> 0), and a
second opinion: a direct solve at r = 1e-30 from u = 0.

It is written from the model's definitions only (the README's model-file table and the doc
comments of truss-core's element.rs, joint.rs, measure.rs, structure/joints.rs); it does not
read, call or reuse the Rust solver (crates/truss-core/src/solver/**): the point is to have
a second, independent computation of the same mathematical problem.

Model (units mm, N, MPa; tension positive)
------------------------------------------
* Nodes X (nominal), displacements u, free DOFs = the directions not fixed by a support.
  Hole nodes of joints are eliminated exactly (below), so they have no DOFs.
* Each member, natural length L0' = natural_length + length error (the sample's), nominal
  vector D = X_j - X_i (L_r = |D|), d = u_j - u_i, current length L = |D + d|, elongation
  without cancellation  e = (2 D.d + d.d)/(L + L_r) + (L_r - L0').
* Bar: k = E A / L0', N = k e, W = k e^2 / 2.
* Cable ("cable"): N = k e for e >= 0, r k e for e < 0; W = k e^2/2 or r k e^2/2. A cable of
  compression_ratio 0 in the model takes the continuation's r; a cable with a ratio > 0 in
  the model keeps that ratio (a model choice) at every r.
* A member with one or both ends in a joint's hole acts between the joints' SHAFT nodes, as
  a bar with a dead band: total clearance G = sum of its joints' clearances (the sample's),
  series stiffness k_s = 1/(L0'/(E A) + sum 1/k_t), e as above with the shafts' positions:
      N = k_s (e - G) for e > G,  0 for |e| <= G,  k_s (e + G) for e < -G,
      W = k_s max(|e| - G, 0)^2 / 2       (no regularisation of the dead band).
* Loads f (if any): Pi(u) = sum W - f.u. Equilibrium: a stationary point (local minimum) of Pi.
* Gradient: node j gets +N n, node i gets -N n (n = (D + d)/L). Tangent stiffness of a
  member: K = k_e n n^T + (N/L)(I - n n^T) in the (i,i) and (j,j) blocks, -K in (i,j), (j,i);
  k_e the current side's stiffness (0 inside a dead band).
* theta_P: top-surface nodes p1, p2, p3 (current positions), n_t = (p2-p1) x (p3-p1),
  theta_P = atan2(|n_t x n_b|, n_t . n_b), n_b the reference normal.

Method
------
Damped Newton on Pi, all in the working precision (every number an arb midpoint):
* direction: the Newton step from a Cholesky factorisation of the tangent stiffness H; where
  H is not positive definite (compressed bars make the racking of a stage held only by slack
  cables unstable), the saddle-free Newton step p = -sum_i v_i (v_i.g)/|lambda_i| from H's
  eigendecomposition (flint's eig), plus the most negative eigenvector, downhill, when that
  step has almost nothing along it; a shifted Cholesky (H + lambda I) if the eigensolve fails;
* step cap: no node moves more than --max-move mm (default 1) in a step;
* exact line search: Pi is C^1 and piecewise smooth; the breakpoints along the ray (where a
  cable's e = 0 or a band's |e| = G, roots of a quadratic in t) are computed exactly, the
  directional derivative phi'(t) = grad Pi(u + t p) . p is scanned at them in increasing
  order, and the first zero of phi' (the first local minimum along the ray) is found in its
  smooth piece by false position (Illinois) to |phi'(t)| <= 1e-12 |phi'(0)|; t = 1 is taken
  when it already meets that;
* converged: the largest gradient component is below --tol (default 1e-40) times the force
  scale (the largest |N| of any member, at least 1e-12 N) AND the remaining Newton step (the
  displacement error to first order) moves no node more than 1e-20 mm (at r = 1e-30 a slack
  cable's stiffness is ~4e-28 N/mm, so a small gradient alone does not pin the soft modes);
* stalled: the residual has not fallen below a tenth of its best in --stall iterations
  (default 100; --stall-direct 60 for the direct solve); the solve then stops, unconverged.
Continuation: r = 1e-4 from u = 0, then r = 1e-5, ..., 1e-30, each from the previous solution.
"Settled": every level converged and theta_P at r = 1e-20, 1e-25, 1e-30 agree to 1e-10
relative; the limit is then theta_P(1e-30). The direct solve at r = 1e-30 from u = 0 is a
second opinion; the sample's line says where the two disagree (theta, energy, and which
members are slack, at their kink, loose or at their band's edge in one and not the other).
Member states (at the final r): a cable is "at its kink" when |e| <= --kink-tol (1e-15 mm)
and "slack" when e < -kink-tol (slack_any: every e < 0); a band is "at its edge" when
||e| - G| <= kink-tol and "loose" when |e| < G - kink-tol. In a floating stage (loose
longerons, slack diagonals) the limit puts many cables exactly at their kink (e = 0 to the
working precision) and longerons exactly at their band's edge; a double-precision solver
sees their sign as noise, so compare slack counts with kinks in mind.

Usage
-----
  python3 scripts/limit_reference.py --model MODEL.json --inputs INPUTS.csv --out OUT.jsonl
          [--range A..B] [--jobs N] [--dps D] [--resume] [--double-s0]
          [--last-exponent N --no-direct]     (quick checks: stop at r = 1e-N, skip the direct solve)
--double-s0 rounds s0 = L_r - L0' the way double-precision code does ((|D| in double -
natural_length) - error) instead of exactly: the nominal lengths' rounding (~5e-14 mm, a
gradient of ~1.5e-10 N) is then the same as the Rust tools', for comparisons below 1e-11.
One JSON line per sample, in index order: index, case, sample, theta_p_by_r (rad, decimal
strings, 25 significant digits), settled, limit_theta_p (null unless settled), direct_theta_p,
iterations (Newton iterations of the whole continuation), slack, loose, kinks, band_edges
(counts at r = 1e-30; *_ids the member ids), residual (N, the final largest gradient
component; residual_rel over the force scale), energy (N mm), positive_definite and
min_pivot (the final tangent stiffness), state_changes_at_r (the r at which the member states
differ from the previous r's), by_r (per r: iterations, residual, state counts, ...), direct
(the direct solve: theta_p, converged, stalled, iterations, residual, energy and its
difference from the continuation's, state counts, agrees = converged and within 1e-10, and
disagreement: theta_rel, the largest displacement and elongation differences, and the ids
whose state differs), and seconds (wall time of the continuation and of the direct solve).
Branch mode (--start FILE --start-exponent N): the equilibrium can be non-unique (floating
stages: at the same r, equilibria tens of micrometres apart, and the continuation's branch
can end in a fold and jump); to check a solver's answer for a sample, give its displacements
and the continuation starts from them at r = 1e-N and follows that branch down to 1e-30;
the line's "start" holds theta_P and the gradient at the given displacements.
--jobs N solves N samples at a time in separate processes. LIMIT_REFERENCE_VERBOSE=1 prints
every Newton iteration (residual, energy, direction, line search) on stderr.
"""

import argparse
import csv
import json
import math
import multiprocessing
import os
import sys
import time

try:
    from flint import arb, arb_mat, ctx
except ImportError:  # pragma: no cover
    sys.exit("limit_reference.py needs python-flint: pip install python-flint")

R_EXPONENTS = list(range(4, 31))  # r = 1e-4 ... 1e-30
VERBOSE = bool(os.environ.get("LIMIT_REFERENCE_VERBOSE"))  # every Newton iteration on stderr
SETTLE_KEYS = ("1e-20", "1e-25", "1e-30")
SETTLE_REL = 1e-10


def rkey(k):
    return f"{10.0 ** -k:.0e}"


def dec(x, digits=25):
    """A decimal string of an arb's midpoint."""
    return x.mid().str(digits, radius=False)


def fl(x):
    return float(x.mid())


# --------------------------------------------------------------------------------------
# The model
# --------------------------------------------------------------------------------------


class ModelError(Exception):
    pass


class Structure:
    """The model file compiled: DOF numbering, members between shaft nodes, joints."""

    def __init__(self, model):
        nodes = model["nodes"]
        self.xyz = {}
        for n in nodes:
            if n["id"] in self.xyz:
                raise ModelError(f"duplicate node {n['id']!r}")
            self.xyz[n["id"]] = [float(v) for v in n["xyz"]]
        joints = model.get("joints", [])
        self.joints = []
        self.hole_joint = {}
        for k, j in enumerate(joints):
            if float(j.get("compression_ratio", 0.0)) != 0.0:
                raise ModelError(f"joint {j['id']!r}: a regularised dead band (compression_ratio > 0) is not supported")
            if j["hole"] in self.hole_joint:
                raise ModelError(f"node {j['hole']!r} is the hole of two joints")
            self.hole_joint[j["hole"]] = k
            self.joints.append(
                {
                    "id": j["id"],
                    "shaft": j["shaft"],
                    "hole": j["hole"],
                    "clearance": float(j["clearance"]),
                    "tension_stiffness": j.get("tension_stiffness"),
                }
            )
        members = model["members"]
        # A hole carries exactly one member.
        at = {}
        for m in members:
            for nd in m["nodes"]:
                at.setdefault(nd, []).append(m["id"])
        for j in self.joints:
            if len(at.get(j["hole"], [])) != 1:
                raise ModelError(f"joint {j['id']!r}: its hole {j['hole']!r} carries {len(at.get(j['hole'], []))} members, not 1")
            if max(abs(a - b) for a, b in zip(self.xyz[j["hole"]], self.xyz[j["shaft"]])) > 1e-9:
                raise ModelError(f"joint {j['id']!r}: shaft and hole are not at the same position")
        for j in self.joints:
            if j["tension_stiffness"] is None:
                # The README's default: 1e5 x the stiffest member's E A / L at the joint.
                best = 0.0
                for m in members:
                    if j["hole"] in m["nodes"] or j["shaft"] in m["nodes"]:
                        a, b = m["nodes"]
                        length = m.get("natural_length") or math.dist(self.xyz[a], self.xyz[b])
                        best = max(best, float(m["youngs_modulus"]) * float(m["area"]) / length)
                j["tension_stiffness"] = 1e5 * best
                print(f"warning: joint {j['id']}: no tension_stiffness, using {j['tension_stiffness']:.6e}", file=sys.stderr)
            j["tension_stiffness"] = float(j["tension_stiffness"])
        # DOFs: every node but the holes, minus the supports' fixed directions.
        fixed = {}
        for s in model.get("supports", []):
            if s["node"] in self.hole_joint:
                raise ModelError(f"support on the hole node {s['node']!r}")
            fixed.setdefault(s["node"], set()).update("xyz".index(c) for c in s["fixed"])
        self.dof = {}
        ndof = 0
        for n in nodes:
            nid = n["id"]
            if nid in self.hole_joint:
                continue
            idx = []
            for a in range(3):
                if a in fixed.get(nid, ()):
                    idx.append(-1)
                else:
                    idx.append(ndof)
                    ndof += 1
            self.dof[nid] = idx
        self.ndof = ndof
        self.loads = []
        for ld in model.get("loads", []):
            if ld["node"] in self.hole_joint:
                raise ModelError(f"load on the hole node {ld['node']!r}")
            self.loads.append((ld["node"], [float(v) for v in ld["force"]]))
        self.members = []
        for m in members:
            a, b = m["nodes"]
            ends = [self.hole_joint.get(a), self.hole_joint.get(b)]
            sa = self.joints[ends[0]]["shaft"] if ends[0] is not None else a
            sb = self.joints[ends[1]]["shaft"] if ends[1] is not None else b
            behaviour = m.get("behaviour", "bar")
            natural = m.get("natural_length")
            if natural is None:
                natural = math.dist(self.xyz[a], self.xyz[b])
            if behaviour == "cable":
                kind = "cable"
            elif behaviour == "bar":
                kind = "bar"
            else:
                raise ModelError(f"member {m['id']!r}: unknown behaviour {behaviour!r}")
            band = [k for k in ends if k is not None]
            if band:
                if kind == "cable":
                    raise ModelError(f"member {m['id']!r}: a cable in a clearance hole is not supported")
                kind = "band"
            self.members.append(
                {
                    "id": m["id"],
                    "group": m.get("group"),
                    "shafts": (sa, sb),
                    "kind": kind,
                    "ratio": float(m.get("compression_ratio", 0.0)) if kind == "cable" else None,
                    "natural_length": float(natural),
                    "rigidity": (float(m["youngs_modulus"]), float(m["area"])),
                    "joints": band,
                }
            )
        self.member_index = {m["id"]: k for k, m in enumerate(self.members)}
        self.joint_index = {j["id"]: k for k, j in enumerate(self.joints)}
        top = model.get("top_surface")
        if not top:
            raise ModelError("the model has no top_surface")
        self.top = list(top["nodes"])
        self.normal = [float(v) for v in top.get("reference_normal", [0.0, 0.0, 1.0])]
        for nd in self.top:
            if nd not in self.dof:
                raise ModelError(f"top surface node {nd!r} is a hole node")


class Sample:
    """One sample's high-precision problem: constants per member, energy, gradient, Hessian."""

    def __init__(self, st, length_errors, clearances, double_s0=False):
        self.st = st
        self.n = st.ndof
        zero = arb(0)
        self.zero = zero
        self.members = []
        for k, m in enumerate(st.members):
            sa, sb = m["shafts"]
            xa, xb = st.xyz[sa], st.xyz[sb]
            D = [arb(xb[c]) - arb(xa[c]) for c in range(3)]  # exact
            Lr = (D[0] * D[0] + D[1] * D[1] + D[2] * D[2]).sqrt()
            L0 = arb(m["natural_length"]) + arb(length_errors[k])  # L0' (exact sum)
            E, A = m["rigidity"]
            EA = arb(E) * arb(A)
            if m["kind"] == "band":
                comp = L0 / EA
                G = zero
                for j in m["joints"]:
                    comp = comp + 1 / arb(st.joints[j]["tension_stiffness"])
                    G = G + arb(clearances[j])
                k_ax = 1 / comp
            else:
                k_ax = EA / L0
                G = zero
            self.members.append(
                {
                    "kind": m["kind"],
                    "fixed_ratio": (arb(m["ratio"]) if (m["kind"] == "cable" and m["ratio"] > 0) else None),
                    "D": D,
                    "Lr": Lr,
                    "s0": (arb((norm_double([xb[c] - xa[c] for c in range(3)]) - m["natural_length"])
                               - length_errors[k]) if double_s0 else Lr - L0),
                    "k": k_ax,
                    "G": G,
                    "ia": st.dof[sa],
                    "ib": st.dof[sb],
                }
            )
        self.fext = [zero] * self.n
        for nd, f in st.loads:
            for c in range(3):
                i = st.dof[nd][c]
                if i >= 0:
                    self.fext[i] = self.fext[i] + arb(f[c])
        self.top = [(st.xyz[nd], st.dof[nd]) for nd in st.top]
        self.nb = [arb(v) for v in st.normal]

    # ---- one member ------------------------------------------------------------------
    def member(self, m, u, r):
        """(c, L, e, N, k_e, W) of member m at displacements u and cable ratio r."""
        ia, ib = m["ia"], m["ib"]
        z = self.zero
        d = [(u[ib[c]] if ib[c] >= 0 else z) - (u[ia[c]] if ia[c] >= 0 else z) for c in range(3)]
        D = m["D"]
        c = [D[0] + d[0], D[1] + d[1], D[2] + d[2]]
        L = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
        e = (2 * (D[0] * d[0] + D[1] * d[1] + D[2] * d[2]) + (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])) / (L + m["Lr"]) + m["s0"]
        k = m["k"]
        kind = m["kind"]
        if kind == "bar":
            ke = k
            N = k * e
            W = N * e / 2
        elif kind == "cable":
            if e >= 0:
                ke = k
            else:
                ke = k * (m["fixed_ratio"] if m["fixed_ratio"] is not None else r)
            N = ke * e
            W = N * e / 2
        else:
            G = m["G"]
            if e > G:
                ke = k
                N = k * (e - G)
                W = N * (e - G) / 2
            elif e < -G:
                ke = k
                N = k * (e + G)
                W = N * (e + G) / 2
            else:
                ke = z
                N = z
                W = z
        return c, L, e, N, ke, W

    def states(self, u, r):
        return [self.member(m, u, r) for m in self.members]

    # ---- gradient and Hessian --------------------------------------------------------
    def evaluate(self, u, r, hessian=True):
        n = self.n
        g = [-f for f in self.fext]
        H = [[self.zero] * n for _ in range(n)] if hessian else None
        energy = self.zero
        for k in range(n):
            energy = energy - self.fext[k] * u[k]
        forces = []
        for m in self.members:
            c, L, e, N, ke, W = self.member(m, u, r)
            energy = energy + W
            forces.append(N)
            inv = 1 / L
            nv = [c[0] * inv, c[1] * inv, c[2] * inv]
            ia, ib = m["ia"], m["ib"]
            for a in range(3):
                f = N * nv[a]
                if ib[a] >= 0:
                    g[ib[a]] = g[ib[a]] + f
                if ia[a] >= 0:
                    g[ia[a]] = g[ia[a]] - f
            if hessian:
                gl = N * inv
                s = ke - gl
                B = [[s * nv[a] * nv[b] + (gl if a == b else 0) for b in range(3)] for a in range(3)]
                for a in range(3):
                    ra, rb = ia[a], ib[a]
                    for b in range(3):
                        ca, cb = ia[b], ib[b]
                        v = B[a][b]
                        if ra >= 0:
                            if ca >= 0:
                                H[ra][ca] = H[ra][ca] + v
                            if cb >= 0:
                                H[ra][cb] = H[ra][cb] - v
                        if rb >= 0:
                            if cb >= 0:
                                H[rb][cb] = H[rb][cb] + v
                            if ca >= 0:
                                H[rb][ca] = H[rb][ca] - v
        g = [x.mid() for x in g]
        if hessian:
            H = [[x.mid() for x in row] for row in H]
        return g, H, forces, energy

    def theta(self, u):
        z = self.zero
        (x1, d1), (x2, d2), (x3, d3) = self.top

        def rel(xa, da, xb, db):
            out = []
            for c in range(3):
                ua = u[da[c]] if da[c] >= 0 else z
                ub = u[db[c]] if db[c] >= 0 else z
                out.append((arb(xb[c]) - arb(xa[c])) + (ub - ua))
            return out

        e1 = rel(x1, d1, x2, d2)
        e2 = rel(x1, d1, x3, d3)
        nt = cross(e1, e2)
        w = cross(nt, self.nb)
        s = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt()
        cth = nt[0] * self.nb[0] + nt[1] * self.nb[1] + nt[2] * self.nb[2]
        return arb.atan2(s, cth)


def norm_double(v):
    """|v| in double precision, in the order a straightforward code sums it."""
    return math.sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2])


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


# --------------------------------------------------------------------------------------
# Linear algebra
# --------------------------------------------------------------------------------------


def cholesky(H, shift):
    """Lower Cholesky factor of H + shift I, or (None, j, pivot) where pivot j is not > 0."""
    n = len(H)
    L = [[None] * n for _ in range(n)]
    for j in range(n):
        Lj = L[j]
        s = H[j][j] + shift
        for k in range(j):
            s = s - Lj[k] * Lj[k]
        s = s.mid()
        if not s > 0:
            return None, j, s
        dj = s.sqrt()
        Lj[j] = dj
        inv = 1 / dj
        for i in range(j + 1, n):
            Li = L[i]
            t = H[i][j]
            for k in range(j):
                t = t - Li[k] * Lj[k]
            Li[j] = (t * inv).mid()
    return L, None, None


def chol_solve(L, b):
    n = len(L)
    y = [None] * n
    for i in range(n):
        s = b[i]
        Li = L[i]
        for k in range(i):
            s = s - Li[k] * y[k]
        y[i] = (s / Li[i]).mid()
    x = [None] * n
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s = s - L[k][i] * x[k]
        x[i] = (s / L[i][i]).mid()
    return x


def newton_direction(H, g):
    """Solve (H + lambda I) p = -g with the smallest lambda >= 0 (of a sequence) that factors."""
    n = len(H)
    scale = max(abs(fl(H[i][i])) for i in range(n)) or 1.0
    shift = arb(0)
    L, j, piv = cholesky(H, shift)
    tries = 0
    lam = None
    while L is None:
        tries += 1
        if tries > 200:
            raise RuntimeError("no positive definite shift found")
        p = abs(fl(piv))
        if lam is None:
            lam = max(2.0 * p, 1e-40 * scale)
        else:
            lam = max(4.0 * lam, 2.0 * p)
        shift = arb(lam)
        L, j, piv = cholesky(H, shift)
    p = chol_solve(L, [-x for x in g])
    return p, (lam or 0.0)


# --------------------------------------------------------------------------------------
# Newton with the exact line search
# --------------------------------------------------------------------------------------


class Settings:
    def __init__(self, tol=1e-40, max_move=1.0, eta=1e-12, max_iter=400, force_floor=1e-12, stall=100, step_tol=1e-20):
        self.tol = tol
        self.step_tol = step_tol
        self.stall = stall
        self.max_move = max_move
        self.eta = eta
        self.max_iter = max_iter
        self.force_floor = force_floor


def axpy(u, t, p):
    return [(a + t * b).mid() for a, b in zip(u, p)]


def dot(a, b):
    s = arb(0)
    for x, y in zip(a, b):
        s = s + x * y
    return s


def max_node_move(sample, p):
    best = 0.0
    for idx in sample.st.dof.values():
        s = 0.0
        for c in idx:
            if c >= 0:
                v = fl(p[c])
                s += v * v
        best = max(best, math.sqrt(s))
    return best


def breakpoints(sample, u, p, hi):
    """The t in (0, hi) where a member along u + t p switches state (a cable's e = 0, a
    band's e = +-G): roots of |c + t q|^2 = l^2, c the current member vector, q its change."""
    z = sample.zero
    out = []
    for m in sample.members:
        kind = m["kind"]
        if kind == "bar" or (kind == "cable" and m["fixed_ratio"] is not None and m["fixed_ratio"] >= 1):
            continue
        ia, ib = m["ia"], m["ib"]
        d = [(u[ib[c]] if ib[c] >= 0 else z) - (u[ia[c]] if ia[c] >= 0 else z) for c in range(3)]
        q = [(p[ib[c]] if ib[c] >= 0 else z) - (p[ia[c]] if ia[c] >= 0 else z) for c in range(3)]
        a = q[0] * q[0] + q[1] * q[1] + q[2] * q[2]
        if not a > 0:
            continue
        D = m["D"]
        cv = [D[0] + d[0], D[1] + d[1], D[2] + d[2]]
        b = 2 * (cv[0] * q[0] + cv[1] * q[1] + cv[2] * q[2])
        # |c|^2 without cancellation against l^2: |c|^2 = Lr^2 + 2 D.d + d.d.
        stretch_sq = 2 * (D[0] * d[0] + D[1] * d[1] + D[2] * d[2]) + (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        L0 = m["Lr"] - m["s0"]
        targets = [L0] if kind == "cable" else [L0 + m["G"], L0 - m["G"]]
        for ell in targets:
            # c0 = |c|^2 - l^2 = (Lr - l)(Lr + l) + stretch_sq
            c0 = (m["Lr"] - ell) * (m["Lr"] + ell) + stretch_sq
            disc = b * b - 4 * a * c0
            if not disc >= 0:
                continue
            sq = disc.sqrt()
            # Stable roots: q1 = -(b + sgn(b) sq)/2, t1 = q1/a, t2 = c0/q1.
            qq = -(b + sq) / 2 if b >= 0 else -(b - sq) / 2
            roots = []
            if qq != 0:
                roots = [qq / a, c0 / qq]
            else:
                roots = [z]
            for t in roots:
                t = t.mid()
                if t > 0 and t < hi:
                    out.append(t)
    out.sort()
    return out


def dphi(sample, u, p, t, r, fp):
    """phi'(t) = grad Pi(u + t p) . p, as sum_m N_m (n_m . q_m) - f . p."""
    ut = axpy(u, t, p)
    z = sample.zero
    s = -fp
    for m in sample.members:
        c, L, e, N, ke, W = sample.member(m, ut, r)
        if N == 0:
            continue
        ia, ib = m["ia"], m["ib"]
        q0 = (p[ib[0]] if ib[0] >= 0 else z) - (p[ia[0]] if ia[0] >= 0 else z)
        q1 = (p[ib[1]] if ib[1] >= 0 else z) - (p[ia[1]] if ia[1] >= 0 else z)
        q2 = (p[ib[2]] if ib[2] >= 0 else z) - (p[ia[2]] if ia[2] >= 0 else z)
        s = s + N * (c[0] * q0 + c[1] * q1 + c[2] * q2) / L
    return s.mid()


def line_search(sample, u, p, d0, r, cfg, stats):
    """The first local minimiser t in (0, t_cap] of phi(t) = Pi(u + t p), phi'(0) = d0 < 0,
    t_cap the step cap. Pi is C^1 and piecewise smooth; the breakpoints along the ray (where
    a member switches state) are found exactly, phi' is scanned at them in increasing
    order, and the root in the first smooth piece where phi' turns >= 0 is found by
    false position (Illinois), all in the working precision."""
    move = max_node_move(sample, p)
    t_cap = arb(cfg.max_move / move) if move > 0 else arb(1)
    eta_abs = abs(d0) * cfg.eta
    fp = dot(sample.fext, p)

    def f(t):
        stats["gradients"] += 1
        return dphi(sample, u, p, t, r, fp)

    one = arb(1)
    t1 = one if one < t_cap else t_cap
    d1 = f(t1)
    if abs(d1) <= eta_abs:
        return t1, t_cap
    # Scan the breakpoints (and t1, t_cap) in increasing order for the first phi' >= 0.
    cands = breakpoints(sample, u, p, t_cap) + [t1, t_cap]
    cands = sorted(cands, key=_arbkey)
    lo, dlo = arb(0), d0
    hi = dhi = None
    for t in cands:
        if not t > lo:
            continue
        d = d1 if t is t1 else f(t)
        if abs(d) <= eta_abs:
            return t, t_cap
        if d > 0:
            hi, dhi = t, d
            break
        lo, dlo = t, d
    if hi is None:
        return t_cap, t_cap
    # Illinois false position on the smooth piece [lo, hi], dlo < 0 < dhi.
    side = 0
    tiny = arb(2) ** (-(ctx.prec - 24))
    for it in range(200):
        t = ((lo * dhi - hi * dlo) / (dhi - dlo)).mid()
        if not (lo < t < hi):
            t = ((lo + hi) / 2).mid()
        d = f(t)
        if abs(d) <= eta_abs or (hi - lo) <= tiny * hi:
            return t, t_cap
        if d < 0:
            lo, dlo = t, d
            if side == -1:
                dhi = dhi / 2
            side = -1
        else:
            hi, dhi = t, d
            if side == 1:
                dlo = dlo / 2
            side = 1
        if it % 8 == 7:  # safeguard against a stall
            tm = ((lo + hi) / 2).mid()
            dm = f(tm)
            if dm < 0:
                lo, dlo = tm, dm
            else:
                hi, dhi = tm, dm
    stats["line_search_unfinished"] += 1
    return t, t_cap


def _arbkey(x):
    # Sort arb midpoints exactly: by their decimal expansion at full precision would be slow;
    # a float key is enough except for near ties, which the scan tolerates (it skips t <= lo).
    return float(x.mid())


def saddle_free_direction(H, g):
    """For an H that is not positive definite: p = -sum_i v_i (v_i.g)/|lambda_i| over H's
    eigenpairs (saddle-free Newton: Newton's step in the positive directions, descent in
    the negative ones), from an eigendecomposition in the working precision; where the
    step has almost nothing along the most negative eigenvector (a saddle), that
    eigenvector is added, pointing downhill. Returns (p, lambda_min) or (None, None)."""
    n = len(H)
    try:
        vals, R = arb_mat(H).eig(right=True, algorithm="approx")
    except (ValueError, ZeroDivisionError):
        return None, None
    lam = [x.real.mid() for x in vals]
    top = max(abs(fl(x)) for x in lam)
    floor = arb(top) * arb(2) ** (-(ctx.prec - 30))
    p = [arb(0)] * n
    imin = min(range(n), key=lambda i: fl(lam[i]))
    vmin = None
    cmin = arb(0)
    for i in range(n):
        v = [R[k, i].real.mid() for k in range(n)]
        nv = dot(v, v).sqrt()
        if not nv > 0:
            return None, None
        v = [(x / nv).mid() for x in v]
        a = abs(lam[i])
        if a < floor:
            a = floor
        c = (dot(v, g) / a).mid()
        p = [(pk - c * vk).mid() for pk, vk in zip(p, v)]
        if i == imin:
            vmin, cmin = v, c
    if lam[imin] < 0:
        pn = dot(p, p).sqrt()
        if abs(cmin) < pn * arb(1e-3):
            gv = dot(g, vmin)
            sgn = -1 if gv > 0 else 1
            if not (gv > 0 or gv < 0):
                big = max(range(n), key=lambda i: abs(fl(vmin[i])))
                sgn = 1 if vmin[big] > 0 else -1
            scale = pn if pn > 0 else arb(1e-3)
            p = [(pk + sgn * scale * vk).mid() for pk, vk in zip(p, vmin)]
    return p, fl(lam[imin])


def solve(sample, u, r, cfg, max_iter=None):
    """Damped Newton from u at ratio r. Returns (u, info). Stops when converged, after
    max_iter iterations, or when the residual has not fallen below a tenth of its best in
    cfg.stall iterations (stalled)."""
    max_iter = max_iter or cfg.max_iter
    best, best_it = float("inf"), 0
    stats = {"gradients": 0, "shifted": 0, "capped": 0, "saddle_free": 0, "line_search_unfinished": 0}
    it = 0
    while True:
        g, H, forces, energy = sample.evaluate(u, r, hessian=True)
        res = max((abs(fl(x)) for x in g), default=0.0)
        fscale = max(max((abs(fl(N)) for N in forces), default=0.0), cfg.force_floor)
        if res < 0.1 * best:
            best, best_it = res, it
        L, _, _ = cholesky(H, arb(0))
        kind = "newton"
        if L is not None:
            p = chol_solve(L, [-x for x in g])
            step = max_node_move(sample, p)
            # Converged: the gradient is below tol x the force scale, and the Newton step
            # that remains (the displacement error, to first order) is below step_tol.
            if res <= cfg.tol * fscale and step <= cfg.step_tol:
                return u, dict(converged=True, stalled=False, iterations=it, residual=res, force_scale=fscale,
                               energy=energy, last_step=step, **stats)
        stalled = it - best_it >= cfg.stall
        if it >= max_iter or stalled:
            return u, dict(converged=False, stalled=stalled, iterations=it, residual=res, force_scale=fscale,
                           energy=energy, last_step=None, **stats)
        if L is None:
            p, lam_min = saddle_free_direction(H, g)
            if p is not None:
                kind = f"saddle-free (lambda_min {lam_min:.2e})"
                stats["saddle_free"] += 1
            else:
                p, lam = newton_direction(H, g)
                kind = f"shifted {lam:.2e}"
                stats["shifted"] += 1
        d0 = dot(g, p).mid()
        if not d0 < 0:
            if kind.startswith("saddle-free") and dot(p, p) > 0:
                d0 = -(abs(d0) + arb(res) * arb(1e-30))  # at a saddle: either side descends
            else:
                p = [-x for x in g]
                d0 = dot(g, p).mid()
                kind = "steepest descent"
        if VERBOSE:
            print(f"    r={fl(r):.0e} it {it}: res {res:.3e} scale {fscale:.3e} energy {fl(energy):.17e} {kind}", file=sys.stderr)
        ng = stats["gradients"]
        t, t_cap = line_search(sample, u, p, d0, r, cfg, stats)
        if VERBOSE:
            print(f"      step t {fl(t):.6e} cap {fl(t_cap):.3e} line-search evaluations {stats['gradients'] - ng}", file=sys.stderr)
        if t >= t_cap * (1 - 1e-12) and t_cap < 1:
            stats["capped"] += 1
        u = axpy(u, t, p)
        it += 1


def is_pd(sample, u, r):
    _, H, _, _ = sample.evaluate(u, r, hessian=True)
    L, j, piv = cholesky(H, arb(0))
    if L is None:
        return False, None
    return True, min(fl(L[i][i]) ** 2 for i in range(len(L)))


def classify(sample, u, r, tol):
    """Member states at u: a cable is at its kink when |e| <= tol, slack when e < -tol; a
    band (a member in clearance holes) is at its edge when ||e| - G| <= tol, loose when
    |e| < G - tol. slack_any counts every cable with e < 0 (kinks included)."""
    st = sample.st
    slack, slack_any, loose, kinks, edges = [], [], [], [], []
    min_cable = None
    for k, (m, s) in enumerate(zip(sample.members, sample.states(u, r))):
        e = fl(s[2])
        mid = st.members[k]["id"]
        if m["kind"] == "cable":
            min_cable = abs(e) if min_cable is None else min(min_cable, abs(e))
            if s[2] < 0:
                slack_any.append(mid)
            if abs(e) <= tol:
                kinks.append(mid)
            elif e < 0:
                slack.append(mid)
        elif m["kind"] == "band":
            over = fl(abs(s[2]) - m["G"])
            if abs(over) <= tol:
                edges.append(mid)
            elif over < 0:
                loose.append(mid)
    return dict(slack=slack, slack_any=slack_any, loose=loose, kinks=kinks, edges=edges, min_cable_abs_e=min_cable)


# --------------------------------------------------------------------------------------
# One sample
# --------------------------------------------------------------------------------------

_STRUCT = None
_ARGS = None


def _init(model, args):
    global _STRUCT, _ARGS
    ctx.prec = args["prec"]
    _STRUCT = Structure(model)
    _ARGS = args


def run_sample(row):
    t0 = time.time()
    args = _ARGS
    st = _STRUCT
    sample = Sample(st, row["length_errors"], row["clearances"], double_s0=args["double_s0"])
    cfg = Settings(tol=args["tol"], max_move=args["max_move"], max_iter=args["max_iter"], stall=args["stall"])
    kink_tol = args["kink_tol"]
    u = [arb(0)] * st.ndof
    by_r, infos = {}, {}
    total_it = 0
    ok = True
    last = None
    exps = [k for k in R_EXPONENTS if k <= args["last_exponent"]]
    start = None
    if row.get("start") is not None:
        # Branch mode: continue from the given displacements, from r = 1e-start_exponent.
        exps = [k for k in exps if k >= args["start_exponent"]]
        u = [arb(0)] * st.ndof
        for nid, d in row["start"].items():
            idx = st.dof.get(nid)
            if idx is None:
                continue  # a hole node: eliminated
            for c in range(3):
                if idx[c] >= 0:
                    u[idx[c]] = arb(float(d[c]))
        r0 = arb(float(f"1e-{exps[0]}"))
        g0, _, f0, _ = sample.evaluate(u, r0, hessian=False)
        start = {"exponent": exps[0], "theta_p": dec(sample.theta(u)),
                 "residual": max(abs(fl(x)) for x in g0), "force_scale": max(abs(fl(x)) for x in f0)}
    prev_sets, changes = None, []
    for kexp in exps:
        r = arb(float(f"1e-{kexp}"))
        u, info = solve(sample, u, r, cfg, max_iter=(args["max_iter_first"] if kexp == exps[0] else None))
        total_it += info["iterations"]
        ok = ok and info["converged"]
        th = sample.theta(u)
        key = rkey(kexp)
        by_r[key] = dec(th)
        infos[key] = {
            "iterations": info["iterations"],
            "residual": info["residual"],
            "converged": info["converged"],
            "stalled": info["stalled"],
            "shifted": info["shifted"],
            "saddle_free": info["saddle_free"],
            "capped": info["capped"],
            "energy": dec(info["energy"], 30),
            "last_step_mm": info["last_step"],
        }
        c_r = classify(sample, u, r, kink_tol)
        infos[key].update(slack=len(c_r["slack"]), kinks=len(c_r["kinks"]), loose=len(c_r["loose"]),
                          band_edges=len(c_r["edges"]))
        sets = tuple(tuple(c_r[x]) for x in ("slack", "kinks", "loose", "edges"))
        if prev_sets is not None and sets != prev_sets:
            changes.append(key)
        prev_sets = sets
        last = (r, info, th)
    r_final, info_final, th_final = last
    cls = classify(sample, u, r_final, kink_tol)
    pd, min_pivot = is_pd(sample, u, r_final)
    ths = [float(arb(by_r[k])) for k in SETTLE_KEYS if k in by_r] or [float(arb(by_r[rkey(exps[-1])]))]
    ref = abs(ths[-1]) if ths[-1] != 0 else 1.0
    spread = (max(ths) - min(ths)) / ref if len(ths) == len(SETTLE_KEYS) else None
    settled = bool(ok and spread is not None and spread <= SETTLE_REL)
    # Also the r at which theta is within 1e-10 of the final value for good.
    settle_from = None
    for kexp in reversed(exps):
        v = float(arb(by_r[rkey(kexp)]))
        if abs(v - ths[-1]) <= SETTLE_REL * ref:
            settle_from = rkey(kexp)
        else:
            break
    u_cont = u
    t1 = time.time()
    if not args["direct"]:
        return {
            "index": row["index"], "case": row["case"], "sample": row["sample"],
            "theta_p_by_r": by_r, "settled": settled, "iterations": total_it, "converged": ok,
            "residual": info_final["residual"], "residual_rel": info_final["residual"] / info_final["force_scale"],
            "slack": len(cls["slack"]), "slack_any": len(cls["slack_any"]), "loose": len(cls["loose"]),
            "kinks": len(cls["kinks"]), "band_edges": len(cls["edges"]), "slack_ids": cls["slack"],
            "loose_ids": cls["loose"], "kink_ids": cls["kinks"], "band_edge_ids": cls["edges"],
            "state_changes_at_r": changes, "energy": dec(info_final["energy"], 30),
            "positive_definite": pd, "min_pivot": min_pivot,
            "by_r": infos, "start": start, "seconds": {"continuation": round(t1 - t0, 3)},
        }
    # The direct solve at r = 1e-30 from u = 0.
    r_dir = arb(float(f"1e-{R_EXPONENTS[-1]}"))
    cfg_direct = Settings(tol=args["tol"], max_move=args["max_move"], stall=args["stall_direct"])
    ud, dinfo = solve(sample, [arb(0)] * st.ndof, r_dir, cfg_direct, max_iter=args["max_iter_direct"])
    thd = sample.theta(ud)
    dcls = classify(sample, ud, r_dir, kink_tol)
    dpd, _ = is_pd(sample, ud, r_dir)
    rel = abs(fl(thd) - ths[-1]) / ref
    umax = max((abs(fl(a - b)) for a, b in zip(u_cont, ud)), default=0.0)
    e_cont = sample.states(u_cont, r_final)
    e_dir = sample.states(ud, r_dir)
    e_diff = max((abs(fl(a[2] - b[2])) for a, b in zip(e_cont, e_dir)), default=0.0)
    disagree = {
        "theta_rel": rel,
        "max_displacement_diff_mm": umax,
        "max_elongation_diff_mm": e_diff,
        "slack_only_continuation": sorted(set(cls["slack"]) - set(dcls["slack"])),
        "slack_only_direct": sorted(set(dcls["slack"]) - set(cls["slack"])),
        "kink_only_continuation": sorted(set(cls["kinks"]) - set(dcls["kinks"])),
        "kink_only_direct": sorted(set(dcls["kinks"]) - set(cls["kinks"])),
        "loose_only_continuation": sorted(set(cls["loose"]) - set(dcls["loose"])),
        "loose_only_direct": sorted(set(dcls["loose"]) - set(cls["loose"])),
        "edge_only_continuation": sorted(set(cls["edges"]) - set(dcls["edges"])),
        "edge_only_direct": sorted(set(dcls["edges"]) - set(cls["edges"])),
    }
    t2 = time.time()
    out = {
        "index": row["index"],
        "case": row["case"],
        "sample": row["sample"],
        "theta_p_by_r": by_r,
        "settled": settled,
        "settle_spread": spread,
        "settled_from_r": settle_from,
        "limit_theta_p": by_r[rkey(exps[-1])] if settled else None,
        "theta_p_r_min": by_r[rkey(exps[-1])],
        "theta_p_radius": float(th_final.rad()),
        "direct_theta_p": dec(thd),
        "iterations": total_it,
        "converged": ok,
        "energy": dec(info_final["energy"], 30),
        "residual": info_final["residual"],
        "residual_rel": info_final["residual"] / info_final["force_scale"],
        "force_scale": info_final["force_scale"],
        "positive_definite": pd,
        "min_pivot": min_pivot,
        "slack": len(cls["slack"]),
        "slack_any": len(cls["slack_any"]),
        "loose": len(cls["loose"]),
        "kinks": len(cls["kinks"]),
        "band_edges": len(cls["edges"]),
        "state_changes_at_r": changes,
        "slack_ids": cls["slack"],
        "loose_ids": cls["loose"],
        "kink_ids": cls["kinks"],
        "band_edge_ids": cls["edges"],
        "min_cable_abs_e": cls["min_cable_abs_e"],
        "by_r": infos,
        "start": start,
        "direct": {
            "theta_p": dec(thd),
            "converged": dinfo["converged"],
            "stalled": dinfo["stalled"],
            "energy": dec(dinfo["energy"], 30),
            "energy_minus_continuation": fl(dinfo["energy"] - info_final["energy"]),
            "saddle_free": dinfo["saddle_free"],
            "iterations": dinfo["iterations"],
            "residual": dinfo["residual"],
            "residual_rel": dinfo["residual"] / dinfo["force_scale"],
            "shifted": dinfo["shifted"],
            "capped": dinfo["capped"],
            "positive_definite": dpd,
            "slack": len(dcls["slack"]),
            "loose": len(dcls["loose"]),
            "kinks": len(dcls["kinks"]),
            "band_edges": len(dcls["edges"]),
            "agrees": bool(dinfo["converged"] and rel <= SETTLE_REL),
            "disagreement": disagree,
        },
        "seconds": {"continuation": round(t1 - t0, 3), "direct": round(t2 - t1, 3)},
    }
    return out


# --------------------------------------------------------------------------------------
# Inputs
# --------------------------------------------------------------------------------------


def parse_range(text):
    a, _, b = text.partition("..")
    return int(a), int(b)


def read_inputs(path, st, rng):
    rows = []
    with open(path, newline="") as fh:
        reader = csv.reader(fh)
        header = next(reader)
        col = {h: i for i, h in enumerate(header)}
        for need in ("index", "case", "sample"):
            if need not in col:
                raise ModelError(f"{path}: no column {need!r}")
        mcols = []
        for m in st.members:
            key = "length_error:" + m["id"]
            if key not in col:
                raise ModelError(f"{path}: no column {key!r}")
            mcols.append(col[key])
        jcols = []
        have_clear = any(h.startswith("clearance:") for h in header)
        for j in st.joints:
            key = "clearance:" + j["id"]
            if key in col:
                jcols.append(col[key])
            elif have_clear:
                raise ModelError(f"{path}: no column {key!r}")
            else:
                jcols.append(None)
        if st.joints and not have_clear:
            print("warning: the inputs have no clearance columns: using the model's clearances", file=sys.stderr)
        known = {"index", "case", "sample"} | {"length_error:" + m["id"] for m in st.members} | {"clearance:" + j["id"] for j in st.joints}
        extra = [h for h in header if h not in known]
        if extra:
            raise ModelError(f"{path}: columns the model does not have: {extra[:5]}")
        for rec in reader:
            index = int(rec[col["index"]])
            if rng and not (rng[0] <= index < rng[1]):
                continue
            le = []
            for c, m in zip(mcols, st.members):
                if rec[c] == "":
                    raise ModelError(f"row {index}: member {m['id']} not in this sample's model")
                le.append(float(rec[c]))
            cl = []
            for c, j in zip(jcols, st.joints):
                cl.append(float(rec[c]) if c is not None and rec[c] != "" else j["clearance"])
            rows.append(
                {
                    "index": index,
                    "case": rec[col["case"]],
                    "sample": int(rec[col["sample"]]),
                    "length_errors": le,
                    "clearances": cl,
                }
            )
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True, help="model file (JSON, truss model ...)")
    ap.add_argument("--inputs", required=True, help="mc-shard inputs CSV")
    ap.add_argument("--out", required=True, help="output JSON Lines")
    ap.add_argument("--range", help="global sample indices A..B")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    ap.add_argument("--dps", type=int, default=96, help="working precision in decimal digits (default 96)")
    ap.add_argument("--tol", type=float, default=1e-40, help="gradient tolerance relative to the force scale")
    ap.add_argument("--max-move", type=float, default=1.0, help="step cap: largest node move per step (mm)")
    ap.add_argument("--max-iter", type=int, default=400, help="Newton iterations per continuation step")
    ap.add_argument("--max-iter-first", type=int, default=1000, help="Newton iterations at r = 1e-4 from u = 0")
    ap.add_argument("--max-iter-direct", type=int, default=1500, help="Newton iterations of the direct solve")
    ap.add_argument("--stall", type=int, default=100, help="stop a solve whose residual has not fallen tenfold in this many iterations")
    ap.add_argument("--stall-direct", type=int, default=60, help="the same for the direct solve")
    ap.add_argument("--kink-tol", type=float, default=1e-15,
                    help="a cable with |e| <= this (mm) is at its kink, a band with ||e| - G| <= this at its edge")
    ap.add_argument("--last-exponent", type=int, default=30, help="continue down to r = 1e-N (default 30; for checks)")
    ap.add_argument("--no-direct", action="store_true", help="skip the direct solve (for checks)")
    ap.add_argument("--double-s0", action="store_true",
                    help="round the initial stretch s0 = L_r - L0' as double-precision code does: "
                         "(|D| in double - natural_length) - error (default: exact)")
    ap.add_argument("--start", help="branch mode: JSON Lines of {index, displacements: {node: [x, y, z]}} "
                    "(mc-shard reproduce --detail's displacements); continue each listed sample's "
                    "equilibrium from there, from r = 1e-START_EXPONENT down (other samples are skipped)")
    ap.add_argument("--start-exponent", type=int, default=7, help="branch mode's first r = 1e-N (default 7)")
    ap.add_argument("--resume", action="store_true", help="keep the lines already in --out, solve the rest")
    a = ap.parse_args()
    with open(a.model) as fh:
        model = json.load(fh)
    st = Structure(model)
    rng = parse_range(a.range) if a.range else None
    rows = read_inputs(a.inputs, st, rng)
    if a.start:
        starts = {}
        with open(a.start) as fh:
            for line in fh:
                if line.strip():
                    rec = json.loads(line)
                    starts[int(rec["index"])] = rec["displacements"]
        for row in rows:
            row["start"] = starts.get(row["index"])
        rows = [row for row in rows if row["start"] is not None]
    done = set()
    mode = "w"
    if a.resume and os.path.exists(a.out):
        with open(a.out) as fh:
            for line in fh:
                try:
                    done.add(json.loads(line)["index"])
                except (ValueError, KeyError):
                    pass
        mode = "a"
    rows = [r for r in rows if r["index"] not in done]
    args = {
        "prec": int(math.ceil(a.dps * math.log2(10))) + 8,
        "tol": a.tol,
        "max_move": a.max_move,
        "max_iter": a.max_iter,
        "max_iter_first": a.max_iter_first,
        "max_iter_direct": a.max_iter_direct,
        "kink_tol": a.kink_tol,
        "stall": a.stall,
        "stall_direct": a.stall_direct,
        "last_exponent": a.last_exponent,
        "direct": not a.no_direct,
        "double_s0": a.double_s0,
        "start_exponent": a.start_exponent,
    }
    print(f"limit_reference: {len(rows)} samples, {st.ndof} DOFs, {len(st.members)} members, {len(st.joints)} joints, "
          f"{args['prec']} bits, {a.jobs} process(es)", file=sys.stderr)
    t0 = time.time()
    with open(a.out, mode) as out:
        if a.jobs <= 1:
            _init(model, args)
            results = map(run_sample, rows)
            pool = None
        else:
            pool = multiprocessing.Pool(a.jobs, initializer=_init, initargs=(model, args))
            results = pool.imap(run_sample, rows, chunksize=1)
        n = 0
        for res in results:
            out.write(json.dumps(res) + "\n")
            out.flush()
            n += 1
            last = list(res["theta_p_by_r"])[-1]
            direct = f" direct-agrees {res['direct']['agrees']}" if "direct" in res else ""
            print(f"  [{n}/{len(rows)}] index {res['index']}: theta({last}) {float(res['theta_p_by_r'][last]):.10e} "
                  f"settled {res['settled']}{direct} ({sum(res['seconds'].values()):.1f} s, {time.time() - t0:.0f} s total)",
                  file=sys.stderr)
        if pool:
            pool.close()
            pool.join()


if __name__ == "__main__":
    main()
