"""Strain and stress measures (thesis tables 4.1-4.4): one registry, names carry their units.

Every measure is a function of the displacement (n, 3) [mm], the strain tensor (n, 3, 3) and the
stress tensor (n, 3, 3) [MPa] at n points (plane strain: eps_zz = 0, sigma_zz from Hooke's law).
Strains are tensor components (eps_xy = half the engineering shear strain). Principal values are
sorted 1 >= 2 >= 3; tension is positive.

    from fem.core.measures import MEASURES, evaluate
    MEASURES["sed_MPa"].description
    evaluate(["sed_MPa", "max_compressive_strain"], state)   # -> {name: (n,) array}
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

from fingertip.errors import InputError


class State:
    """Kinematic and static state at n points: displacement (n, 3), strain and stress (n, 3, 3);
    energy (n,) the stored energy per reference volume where it is not sigma:eps / 2 (finite
    kinematics: Green-Lagrange strain, Cauchy stress and the neo-Hookean energy), else None."""

    def __init__(self, displacement: np.ndarray, strain: np.ndarray, stress: np.ndarray, energy=None):
        self.displacement, self.strain, self.stress, self.energy = displacement, strain, stress, energy

    @cached_property
    def principal_strain(self) -> np.ndarray:
        """(n, 3) principal strains, descending."""
        return np.linalg.eigvalsh(self.strain)[:, ::-1]

    @cached_property
    def principal_stress(self) -> np.ndarray:
        """(n, 3) principal stresses [MPa], descending."""
        return np.linalg.eigvalsh(self.stress)[:, ::-1]


@dataclass(frozen=True)
class Measure:
    name: str
    unit: str          # "mm", "MPa" or "1" (dimensionless)
    description: str
    func: Callable[[State], np.ndarray]


MEASURES: dict[str, Measure] = {}


def _add(name, unit, description, func):
    MEASURES[name] = Measure(name, unit, description, func)


_AX = "xyz"
for _i, _a in enumerate(_AX):
    _add(f"displacement_{_a}_mm", "mm", f"displacement along {_a}", lambda s, i=_i: s.displacement[:, i])
_add("displacement_magnitude_mm", "mm", "length of the displacement vector",
     lambda s: np.linalg.norm(s.displacement, axis=1))
for _i, _j in ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)):
    _c = _AX[_i] + _AX[_j]
    _add(f"strain_{_c}", "1", f"strain tensor component {_c}", lambda s, i=_i, j=_j: s.strain[:, i, j])
    _add(f"stress_{_c}_MPa", "MPa", f"stress component {_c}", lambda s, i=_i, j=_j: s.stress[:, i, j])
for _k in range(3):
    _add(f"principal_strain_{_k + 1}", "1", f"principal strain {_k + 1} (1 largest)",
         lambda s, k=_k: s.principal_strain[:, k])
    _add(f"principal_stress_{_k + 1}_MPa", "MPa", f"principal stress {_k + 1} (1 largest, tension +)",
         lambda s, k=_k: s.principal_stress[:, k])
_add("sed_MPa", "MPa", "strain energy density sigma:eps / 2 (finite kinematics: the stored energy per reference volume)",
     lambda s: 0.5 * np.einsum("nij,nij->n", s.stress, s.strain) if s.energy is None else s.energy)
_add("max_tensile_strain", "1", "largest principal strain", lambda s: s.principal_strain[:, 0])
_add("max_compressive_strain", "1", "minus the smallest principal strain (positive in compression)",
     lambda s: -s.principal_strain[:, 2])
_add("max_shear_strain", "1", "maximum tensor shear strain (eps_1 - eps_3) / 2",
     lambda s: 0.5 * (s.principal_strain[:, 0] - s.principal_strain[:, 2]))
_add("max_shear_stress_MPa", "MPa", "maximum shear stress (sigma_1 - sigma_3) / 2",
     lambda s: 0.5 * (s.principal_stress[:, 0] - s.principal_stress[:, 2]))
_add("mean_stress_MPa", "MPa", "tr(sigma) / 3 (minus the pressure)", lambda s: np.trace(s.stress, axis1=1, axis2=2) / 3)
_add("volumetric_strain", "1", "tr(eps)", lambda s: np.trace(s.strain, axis1=1, axis2=2))


def _von_mises(s: State) -> np.ndarray:
    dev = s.stress - np.trace(s.stress, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("nij,nij->n", dev, dev))


_add("von_mises_stress_MPa", "MPa", "von Mises equivalent stress", _von_mises)

def check_names(names) -> list[str]:
    """Validate measure names; raise InputError naming the unknown ones."""
    names = list(names)
    unknown = [n for n in names if n not in MEASURES]
    if unknown:
        raise InputError(f"unknown measure(s) {unknown}; known: {', '.join(MEASURES)}")
    return names


def base_measure(candidate: str) -> str:
    """Registry name behind a candidate ('abs:strain_xy' -> 'strain_xy', the magnitude of a signed
    measure); InputError if unknown."""
    name = candidate[4:] if candidate.startswith("abs:") else candidate
    if name not in MEASURES:
        raise InputError(f"unknown measure '{candidate}': use a fem.core.measures name (e.g. sed_MPa, "
                         f"max_compressive_strain) or abs:<name>; known: {', '.join(MEASURES)}")
    return name


def evaluate(names, state: State) -> dict[str, np.ndarray]:
    """{name: (n,) values} for the given measure names (all if None)."""
    return {n: MEASURES[n].func(state) for n in check_names(MEASURES if names is None else names)}


def describe() -> str:
    """One line per measure: name, unit, description (for --help texts and docs)."""
    return "\n".join(f"{m.name:28s} [{m.unit}] {m.description}" for m in MEASURES.values())
