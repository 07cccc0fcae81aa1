"""Models and single solves: the paper's prism (any Table 1 value overridden, as a job's
``{"prism": {...}}`` takes them), model files, and one equilibrium with the numbers
``truss solve`` prints. Units: mm, N, MPa, rad."""

from __future__ import annotations

import json
import math
import numbers
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _columns, _native
from .errors import InvalidInputError

__all__ = ["Model", "Solution", "prism", "solve"]


class Model:
    """A validated truss model (nodes, members, supports, loads, top surface, joints)."""

    def __init__(self, native: _native.Model) -> None:
        self._native = native

    @staticmethod
    def from_file(path: Union[str, "os.PathLike[str]"]) -> "Model":
        """Reads and validates a model file (JSON, as ``truss model`` writes it)."""
        return Model(_native.Model.from_file(os.fspath(path)))

    @staticmethod
    def from_json(text: str, origin: str = "<string>") -> "Model":
        """Parses and validates a model file's text; ``origin`` names it in messages."""
        return Model(_native.Model.from_json(text, origin))

    @property
    def node_ids(self) -> List[str]:
        """Node ids, model order."""
        return self._native.node_ids

    @property
    def member_ids(self) -> List[str]:
        """Member ids, model order."""
        return self._native.member_ids

    @property
    def member_groups(self) -> List[str]:
        """Each member's group (``batten``, ``longeron``, ``diagonal``, …), model order."""
        return self._native.member_groups

    @property
    def joint_ids(self) -> List[str]:
        """Backlash joint ids, model order (empty without joints)."""
        return self._native.joint_ids

    def to_json(self) -> str:
        """The model file's text, every default written out."""
        return self._native.to_json()

    def solve(self, length_errors: Optional[Mapping[str, float]] = None) -> "Solution":
        """See :func:`solve`."""
        return solve(self, length_errors)

    def __repr__(self) -> str:
        return repr(self._native)


def prism(
    stages: int = 5,
    *,
    backlash: Union[bool, Mapping[str, float], None] = None,
    side: Optional[float] = None,
    height: Optional[float] = None,
    batten_area: Optional[float] = None,
    batten_modulus: Optional[float] = None,
    longeron_area: Optional[float] = None,
    longeron_modulus: Optional[float] = None,
    diagonal_area: Optional[float] = None,
    diagonal_modulus: Optional[float] = None,
    diagonal_length: Union[float, str, None] = None,
    compression_ratio: Optional[float] = None,
) -> Model:
    """The paper's N-stage triangular prism (section 2.1, Table 1). Every option left at None
    keeps Table 1's value; they are the fields of a job's ``{"prism": {...}}``: lengths in mm,
    areas in mm², moduli in MPa, ``diagonal_length`` a number or ``"exact"``, and
    ``backlash`` True (pin joints with the paper's clearance) or a mapping of
    ``clearance``, ``tension_factor``, ``compression_ratio``. A refused value raises
    :class:`~truss_mc.errors.InvalidInputError` with its ``json_path`` (``prism.side``)."""
    given: Dict[str, Any] = {
        "stages": stages,
        "backlash": dict(backlash) if isinstance(backlash, Mapping) else backlash,
        "side": side,
        "height": height,
        "batten_area": batten_area,
        "batten_modulus": batten_modulus,
        "longeron_area": longeron_area,
        "longeron_modulus": longeron_modulus,
        "diagonal_area": diagonal_area,
        "diagonal_modulus": diagonal_modulus,
        "diagonal_length": diagonal_length,
        "compression_ratio": compression_ratio,
    }
    options = {k: v for k, v in given.items() if v is not None}
    for key, value in options.items():
        if key in ("stages", "backlash") or (key == "diagonal_length" and value == "exact"):
            continue
        _check_option(value, f"prism.{key}")
    if isinstance(options.get("backlash"), dict):
        for key, value in options["backlash"].items():
            _check_option(value, f"prism.backlash.{key}")
    return Model(_native.Model.prism(json.dumps(options, allow_nan=True)))


def _check_number(value: Any, name: str) -> float:
    """``value`` as a float if it is a real number; a bool (which Python would take as 0 or
    1 mm), a string or anything else raises TypeError naming it."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__} {value!r}")
    return float(value)


def _check_option(value: Any, name: str) -> None:
    """A prism option: a real number (else TypeError), finite (else
    :class:`~truss_mc.errors.InvalidInputError` with ``json_path`` ``name``: JSON has no NaN,
    and the job reader's message for one would name no field)."""
    x = _check_number(value, name)
    if not math.isfinite(x):
        e = InvalidInputError(f"{name}: {x} is not a finite number")
        e.json_path = name
        raise e


@dataclass(frozen=True)
class Solution:
    """One equilibrium, with the numbers ``truss solve`` prints."""

    #: Distortion angle θ_P [rad] (None when the model names no top surface).
    theta_p: Optional[float]
    #: tan θ_x of the top surface [-].
    tan_theta_x: Optional[float]
    #: tan θ_y of the top surface [-].
    tan_theta_y: Optional[float]
    #: The top surface centroid's displacement against the bottom's (the supported nodes'),
    #: δ = (u₁ + u₂ + u₃)/3 − Σ s_k/m, along the bottom frame's e_x [mm].
    decenter_x: Optional[float]
    #: δ·e_y, e_y = n_b × e_x [mm].
    decenter_y: Optional[float]
    #: √(decenter_x² + decenter_y²): the shift in the bottom plane [mm].
    decenter: Optional[float]
    #: δ·n_b: the shift along the bottom's normal, signed, positive apart [mm].
    despace: Optional[float]
    #: Newton iterations (linear solves).
    iterations: int
    #: Tangent factorisations.
    factorisations: int
    #: Final out-of-balance force, max over free DOFs [N].
    residual: float
    #: Node ids, the rows of ``displacements``.
    node_ids: List[str]
    #: Node displacements [mm], shape (nodes, 3).
    displacements: np.ndarray
    #: Member ids, the entries of ``forces``.
    member_ids: List[str]
    #: Member axial forces [N], tension positive.
    forces: np.ndarray
    #: Ids of the cables that ended slack.
    slack_cables: List[str]
    #: Joint ids, the rows of the joint arrays.
    joint_ids: List[str]
    #: Each joint's hole-centre offset from its shaft centre [mm], shape (joints, 3).
    joint_offsets: np.ndarray
    #: Each joint's contact force [N] (0 when loose).
    joint_contact: np.ndarray
    #: Whether each joint's pin is loose in its hole.
    joint_loose: np.ndarray

    def displacement(self, node_id: str) -> np.ndarray:
        """The displacement [mm] of node ``node_id``."""
        return np.asarray(self.displacements[self.node_ids.index(node_id)])

    def force(self, member_id: str) -> float:
        """The axial force [N] of member ``member_id``."""
        return float(self.forces[self.member_ids.index(member_id)])


def solve(model: Model, length_errors: Optional[Mapping[str, float]] = None) -> Solution:
    """Solves ``model``'s equilibrium with the member length errors ``{member id: mm}``
    (natural minus nominal length; members not named get none), as ``truss solve`` does.

    Raises :class:`~truss_mc.errors.UsageError` for an unknown member or an error beyond 1 %
    of the member's length, and :class:`~truss_mc.errors.SolveFailedError` when Newton's
    method does not converge. The interpreter lock is released while it solves."""
    if length_errors is None:
        length_errors = {}
    if not isinstance(length_errors, Mapping):
        raise TypeError(
            f"length_errors: expected a mapping {{member id: mm}}, got {type(length_errors).__name__}"
        )
    items = [(str(k), _check_number(v, f'length_errors["{k}"]')) for k, v in length_errors.items()]
    r = model._native.solve(items)
    joints = len(r["joint_ids"])
    return Solution(
        theta_p=r["theta_p"],
        tan_theta_x=r["tan_theta_x"],
        tan_theta_y=r["tan_theta_y"],
        decenter_x=r["decenter_x"],
        decenter_y=r["decenter_y"],
        decenter=r["decenter"],
        despace=r["despace"],
        iterations=r["iterations"],
        factorisations=r["factorisations"],
        residual=r["residual"],
        node_ids=r["node_ids"],
        displacements=_columns.floats(r["displacements"], (len(r["node_ids"]), 3)),
        member_ids=r["member_ids"],
        forces=_columns.floats(r["forces"]),
        slack_cables=r["slack_cables"],
        joint_ids=r["joint_ids"],
        joint_offsets=_columns.floats(r["joint_offsets"], (joints, 3)),
        joint_contact=_columns.floats(r["joint_contact"]),
        joint_loose=np.array(r["joint_loose"], dtype=bool),
    )
