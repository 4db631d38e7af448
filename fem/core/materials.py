"""Per-layer isotropic materials: the `mABCDE` code, explicit moduli, Poisson ratio, rigid bone.

Units: Young's modulus in MPa (1e4 Pa = 0.01 MPa). Layers are positive ints, 1..5 from the
outside in (5 = bone). `Material("m43338")` = 1e4, 1e3, 1e3, 1e3, 1e8 Pa with nu = 0.48.

A code or a list of moduli gives one value per layer number from 1 to the model's highest solid
layer, no more and no fewer (`Material.check_layers`, run where a material meets a mesh): "m3" for
a one-layer block, "m33338" for the 2D cylinder with bone (layers 1 and 5), "m43338" for the
five-layer model. `default_code(layers)` is the default of a model with those layers.

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
"""The homogeneous material with bone: 1 kPa in every soft layer, 100 MPa bone; `default_code`
gives its digits up to a model's highest layer ("m3" for layer 1 alone)."""
LAYERED_CODE = "m43338"
"""The material a five-layer model folder records: the thesis's fitted multi-layer model (6.2.1)."""
RECORDED_CODES = (DEFAULT_CODE, LAYERED_CODE)
"""The codes model folders recorded before codes were checked against a model's layers (a one-layer
2D model recorded "m33338"): where one does not fit the model's layers it is read as
`default_code` of them (`fem.io.modelfolder.folder_material`)."""
DEFAULT_NU = 0.48
"""Poisson ratio of a model whose model.json names none (thesis 4.1: nearly incompressible)."""
NU_MAX = 0.4999
BONE_LAYER = 5
FLUID_LAYER = 6
FLUID_BULK_RATIO = 1e7


def layer_ids(layers) -> set[int]:
    """The distinct layer ids among `layers` (an iterable of ints, or a mesh's (M,) layer array)."""
    values = layers if isinstance(layers, np.ndarray) else list(layers)
    return {int(k) for k in np.unique(np.asarray(values, int))}


def solid_layers(layers) -> list[int]:
    """Sorted distinct solid layer ids among `layers` (`layer_ids`): the fluid core (FLUID_LAYER)
    takes no modulus."""
    return sorted(layer_ids(layers) - {FLUID_LAYER})


def layers_text(layers) -> str:
    """'layers 1-5', 'layers 1 and 5', 'layer 1 only' for a set of layer ids."""
    ids = sorted({int(k) for k in layers})
    if len(ids) == 1:
        return f"layer {ids[0]} only"
    if ids == list(range(ids[0], ids[-1] + 1)) and len(ids) > 2:
        return f"layers {ids[0]}-{ids[-1]}"
    return "layers " + ", ".join(str(k) for k in ids[:-1]) + f" and {ids[-1]}"


def default_code(layers) -> str:
    """The default material code of a model with these layers (ids; a fluid core's is ignored): one
    digit per layer 1 to the highest solid one, LAYERED_CODE for the five-layer model, else the
    digits of DEFAULT_CODE (1 kPa soft layers, 100 MPa bone): "m3" for layer 1 (and 1 with a fluid
    core), "m33338" for layers 1 and 5."""
    solid = solid_layers(layers)
    if solid == [1, 2, 3, 4, 5]:
        return LAYERED_CODE
    digits = DEFAULT_CODE[1:]
    return "m" + "".join(digits[k] if k < len(digits) else digits[0] for k in range(max(solid, default=1)))


def _count(n: int, word: str, plural: str | None = None) -> str:
    """'1 digit', '5 digits'."""
    return f"{n} {word if n == 1 else plural or word + 's'}"


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
        A code or a sequence has one value per layer 1 to the model's highest solid layer
        (`check_layers`); a mapping names the layers it gives.
    nu : Poisson ratio in [0, 0.4999], one for all layers or a mapping layer -> nu.
    rigid : layers treated as rigid (all their nodes fixed at zero displacement) instead of
        elastic; `rigid_bone=True` is shorthand for `rigid=(5,)`.
    """

    E_MPa: dict
    nu: dict
    rigid: frozenset
    code: str | None
    listed: int | None      # moduli given in layer order (code digits, sequence length); None: a mapping

    def __init__(self, spec=DEFAULT_CODE, nu: float | Mapping[int, float] = DEFAULT_NU, rigid=(),
                 rigid_bone: bool = False):
        code, listed = None, None
        if isinstance(spec, Material):
            E, code, listed = dict(spec.E_MPa), spec.code, spec.listed
        elif isinstance(spec, str):
            m = re.fullmatch(r"m(\d+)", spec.strip())
            if not m:
                raise InputError(f"material code '{spec}' is not of the form mABCDE (digit k = "
                                 "log10 of layer k's Young's modulus in Pa), e.g. m43338")
            code = spec.strip()
            E = {k + 1: 10.0 ** (int(d) - 6) for k, d in enumerate(m.group(1))}   # Pa -> MPa
            listed = len(E)
        elif isinstance(spec, Mapping):
            E = {int(k): float(v) for k, v in spec.items()}
        else:
            E = {k + 1: float(v) for k, v in enumerate(np.atleast_1d(spec))}
            listed = len(E)
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
        object.__setattr__(self, "listed", listed)

    def __str__(self):
        name = self.code or "E_MPa=" + ",".join(f"{k}:{v:g}" for k, v in sorted(self.E_MPa.items()))
        return name + (f" (rigid layers {sorted(self.rigid)})" if self.rigid else "")

    def check_layers(self, layers) -> None:
        """InputError unless this material fits a model with these layers (ids, or a mesh's (M,)
        layer array): a code or a sequence gives one value per layer 1 to the highest solid layer
        (the fluid core, FLUID_LAYER, takes none), a mapping a modulus for every solid layer."""
        ids = layer_ids(layers)
        solid = solid_layers(ids)
        n = max(solid, default=0)
        has = layers_text(solid) + (f" (and the fluid core, layer {FLUID_LAYER}, which takes none)"
                                    if FLUID_LAYER in ids else "")
        gaps = sorted(set(range(1, n + 1)) - set(solid))
        absent = f"{layers_text(gaps).replace(' only', '')}: not in this model, any value" if gaps else ""
        if self.listed is not None and self.listed != n and self.code is not None:
            raise InputError(f"material {self.code} has {_count(self.listed, 'digit')} but this model has {has}: "
                             f"give {_count(n, 'digit')} (digit k = log10 of layer k's modulus in Pa"
                             f"{'; ' + absent if absent else ''}), e.g. {default_code(solid)}")
        if self.listed is not None and self.listed != n:
            given = ", ".join(f"{self.E_MPa[k]:g}" for k in sorted(self.E_MPa))
            example = ", ".join(f"{10.0 ** (int(d) - 6):g}" for d in default_code(solid)[1:])
            raise InputError(f"material [{given}] gives {_count(self.listed, 'modulus', 'moduli')} but this model "
                             f"has {has}: give {_count(n, 'modulus', 'moduli')} in MPa, one per layer "
                             f"1{'-' + str(n) if n > 1 else ''}{' (' + absent + ')' if absent else ''}, e.g. [{example}]")
        missing = sorted(set(solid) - set(self.E_MPa))
        if missing:
            raise InputError(f"the mesh has layers {missing} but material {self} defines only "
                             f"layers {sorted(self.E_MPa)}; give a modulus for every layer")

    def lame(self, layer: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lame parameters (mu, lambda) in MPa for each entry of `layer` (int array); InputError
        when the material does not fit the layers (`check_layers`)."""
        layer = np.asarray(layer)
        fluid = layer == FLUID_LAYER
        if fluid.all():
            raise InputError("the mesh is all fluid (layer 6); the fluid needs a solid around it")
        self.check_layers(layer)
        E = np.vectorize(lambda k: self.E_MPa.get(k, np.nan), otypes=[float])(layer)
        nu = np.vectorize(lambda k: self.nu.get(k, np.nan), otypes=[float])(layer)
        mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
        if fluid.any():
            solid = ~fluid & ~np.isin(layer, list(self.rigid))
            mu[fluid] = 0.0
            lam[fluid] = FLUID_BULK_RATIO * (lam[solid] + 2 * mu[solid] / 3).max()
        return mu, lam
