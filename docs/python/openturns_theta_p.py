"""θ_P of the paper's 5-stage truss as an OpenTURNS model function.

truss_mc.solve wrapped as an ``openturns.PythonFunction`` whose inputs are the length errors
of the battens and longerons [mm] and whose output is the distortion angle θ_P [rad]; then a
Monte Carlo with OpenTURNS' own random generator gives θ_P's 95th percentile with a
bootstrap interval, for σ = 6.3 µm on every batten and longeron (the paper's section 3.1;
REPRODUCTION.md gives this project's figure from 50,000 samples of jobs/paper-3.1.json,
1.255e-4 rad). Any other OpenTURNS algorithm (Sobol' indices, FORM, a chaos metamodel) takes
the same function.

Run it from the repository's root once truss_mc and openturns are installed:

    python docs/python/openturns_theta_p.py
"""

from __future__ import annotations

from typing import Dict, List, Sequence

import openturns as ot

import truss_mc

RAD_TO_ARCSEC = 180 / 3.141592653589793 * 3600


def model_function(stages: int = 5) -> "ot.Function":
    """θ_P [rad] of the prism as a function of its battens' and longerons' length errors
    [mm] (natural minus nominal length), in model order."""
    model = truss_mc.prism(stages=stages)
    members: List[str] = [
        m for m, g in zip(model.member_ids, model.member_groups) if g in ("batten", "longeron")
    ]

    def theta_p(x: Sequence[float]) -> List[float]:
        return [truss_mc.solve(model, dict(zip(members, x))).theta_p]

    f = ot.PythonFunction(len(members), 1, theta_p)
    f.setInputDescription(members)
    f.setOutputDescription(["theta_p"])
    return f


def main(sigma: float = 0.0063, samples: int = 2000, seed: int = 1) -> Dict[str, float]:
    """θ_P's 95th percentile [rad] over ``samples`` draws of N(0, σ²) errors, with a 95 %
    bootstrap interval."""
    ot.RandomGenerator.SetSeed(seed)
    f = model_function()
    errors = ot.JointDistribution([ot.Normal(0.0, sigma)] * f.getInputDimension())
    theta = f(errors.getSample(samples))
    p95 = theta.computeQuantilePerComponent(0.95)[0]
    boot = ot.BootstrapExperiment(theta)
    replicates = [boot.generate().computeQuantilePerComponent(0.95)[0] for _ in range(200)]
    lower, upper = ot.Sample([[r] for r in replicates]).computeQuantilePerComponent([0.025, 0.975])
    result = {"p95": p95, "lower": lower[0], "upper": upper[0], "samples": samples}
    print(
        f"θ_P95 = {p95:.4e} rad ({p95 * RAD_TO_ARCSEC:.2f} arcsec), 95 % bootstrap interval "
        f"{lower[0]:.4e} … {upper[0]:.4e} rad, {samples} samples of σ = {sigma} mm"
    )
    return result


if __name__ == "__main__":
    main()
