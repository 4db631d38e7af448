"""Per-layer isotropic materials: the `mABCDE` code, explicit moduli, Poisson ratio, rigid bone.

Units: Young's modulus in MPa (1e4 Pa = 0.01 MPa). Layers are positive ints, 1..5 from the
outside in (5 = bone). `Material("m43338")` = 1e4, 1e3, 1e3, 1e3, 1e8 Pa with nu = 0.48.

Layer 6 (FLUID_LAYER) is an incompressible inviscid fluid (the thesis's solid-fluid model, 4.6):
it needs no modulus. It has no shear stiffness; fem.core.model gives it one uniform pressure per
model, whose bulk modulus is FLUID_BULK_RATIO times the stiffest solid's (the volume is kept to
about 1 / FLUID_BULK_RATIO of the solid's volumetric strain; a larger ratio only loses digits in
the solver's residual check), and holds the fluid's inner nodes, which carry nothing.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from fingertip.errors import InputError

DEFAULT_CODE = "m33338"
"""The material of a model whose model.json names none, and of the homogeneous 2D models: 1 kPa
in every soft layer, 100 MPa bone."""
LAYERED_CODE = "m43338"
"""The material a five-layer model folder records: the thesis's fitted multi-layer model (6.2.1)."""
DEFAULT_NU = 0.48
"""Poisson ratio of a model whose model.json names none (thesis 4.1: nearly incompressible)."""
NU_MAX = 0.4999
BONE_LAYER = 5
FLUID_LAYER = 6
FLUID_BULK_RATIO = 1e7


def _check_nu(nu: float) -> float:
    nu = float(nu)
    if not 0.0 <= nu <= NU_MAX:
        raise InputError(f"Poisson ratio nu = {nu:g} is outside [0, {NU_MAX}]; "
                         f"use {NU_MAX} for a nearly incompressible tissue (0.5 is not supported)")
    return nu


@dataclass(frozen=True)
class Material:
    """One isotropic material per layer.

    Parameters
    ----------
    spec : `mABCDE` code (digit k = log10 of layer k's modulus in Pa), or a mapping
        layer -> Young's modulus in MPa, or a sequence of moduli in MPa for layers 1, 2, ...
    nu : Poisson ratio in [0, 0.4999], one for all layers or a mapping layer -> nu.
    rigid : layers treated as rigid (all their nodes fixed at zero displacement) instead of
        elastic; `rigid_bone=True` is shorthand for `rigid=(5,)`.
    """

    E_MPa: dict
    nu: dict
    rigid: frozenset
    code: str | None

    def __init__(self, spec=DEFAULT_CODE, nu: float | Mapping[int, float] = DEFAULT_NU, rigid=(),
                 rigid_bone: bool = False):
        code = None
        if isinstance(spec, Material):
            E, code = dict(spec.E_MPa), spec.code
        elif isinstance(spec, str):
            m = re.fullmatch(r"m(\d+)", spec.strip())
            if not m:
                raise InputError(f"material code '{spec}' is not of the form mABCDE (digit k = "
                                 "log10 of layer k's Young's modulus in Pa), e.g. m43338")
            code = spec.strip()
            E = {k + 1: 10.0 ** (int(d) - 6) for k, d in enumerate(m.group(1))}   # Pa -> MPa
        elif isinstance(spec, Mapping):
            E = {int(k): float(v) for k, v in spec.items()}
        else:
            E = {k + 1: float(v) for k, v in enumerate(np.atleast_1d(spec))}
        for layer, e in E.items():
            if not (np.isfinite(e) and e > 0):
                raise InputError(f"Young's modulus of layer {layer} is {e:g} MPa; "
                                 "moduli must be positive (give them in MPa, 1e4 Pa = 0.01 MPa)")
        if isinstance(nu, Mapping):
            nus = {int(k): _check_nu(v) for k, v in nu.items()}
            missing = sorted(set(E) - set(nus))
            if missing:
                raise InputError(f"no Poisson ratio for layers {missing}; give nu for every layer")
        else:
            nus = {k: _check_nu(nu) for k in E}
        rigid = frozenset(int(r) for r in rigid) | ({BONE_LAYER} if rigid_bone else frozenset())
        object.__setattr__(self, "E_MPa", E)
        object.__setattr__(self, "nu", nus)
        object.__setattr__(self, "rigid", rigid)
        object.__setattr__(self, "code", code)

    def __str__(self):
        name = self.code or "E_MPa=" + ",".join(f"{k}:{v:g}" for k, v in sorted(self.E_MPa.items()))
        return name + (f" (rigid layers {sorted(self.rigid)})" if self.rigid else "")

    def lame(self, layer: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lame parameters (mu, lambda) in MPa for each entry of `layer` (int array)."""
        layer = np.asarray(layer)
        fluid = layer == FLUID_LAYER
        present = set(np.unique(layer[~fluid]).tolist())
        missing = sorted(present - set(self.E_MPa))
        if missing:
            raise InputError(f"the mesh has layers {missing} but material {self} defines only "
                             f"layers {sorted(self.E_MPa)}; give a modulus for every layer")
        E = np.vectorize(lambda k: self.E_MPa.get(k, np.nan), otypes=[float])(layer)
        nu = np.vectorize(lambda k: self.nu.get(k, np.nan), otypes=[float])(layer)
        mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
        if fluid.any():
            if fluid.all():
                raise InputError("the mesh is all fluid (layer 6); the fluid needs a solid around it")
            solid = ~fluid & ~np.isin(layer, list(self.rigid))
            mu[fluid] = 0.0
            lam[fluid] = FLUID_BULK_RATIO * (lam[solid] + 2 * mu[solid] / 3).max()
        return mu, lam
