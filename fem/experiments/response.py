"""Persisted response models: what a model answers to contact forces on its pad, stored in the
model folder and reused by every later command with the same inputs.

A response model belongs to one (mesh, material and nu, held regions, approach direction, receptor
grid). Over the m contact candidates of the model's contact region (`fem.io.modelfolder.CONTACT_REGION`),
k of which are condensed (`reach`: all when m <= CONDENSE_MAX_NODES, else the ones a scene's
indentors can touch), it holds one row per condensed candidate j, the response to a unit force
along the approach at j:

- WT (k, m) [mm/N]: the displacement along the approach of every candidate; its `reach` columns
  are the compliance C (k, k) of the condensed ones, from the Schur complement of the
  factorisation (no solves), the other columns from solves; its diagonal (k,) kept beside it;
- RT (k, s): the receptor sampler's independent outputs (displacement and strain [-] at the
  receptor points, the first `ReceptorSampler.independent` rows of its operator O), R = O K^-1 B
  transposed: the loads of B sit on condensed rows, so each block of 64 candidates is one
  backward substitution (`fem.core.system.LinearSystem.solve_condensed`); through the transposed
  system B^T K^-1 O^T (full solves) when O has fewer rows than there are condensed candidates.
  Where python-mumps is installed, a model of INVERSE_ENTRIES_FROM_DOFS unknowns or more indented
  along a coordinate axis gets C and R from MUMPS's entries of K^-1 instead (`fem.core.inverse`:
  no Schur complement, pruned substitutions; equal within one rounding step of the rows).
  The stress rows follow from the strain rows point by point (`fem.receptors.grid.complete_outputs`
  with the Lame moduli lame_MPa (n, 2) of each point's element), so they are computed when read,
  not stored (3D: 9 of 15 values per receptor point; 2D: 5 of 9).

Both are kept quantised (`fem.io.rows`): each row rounded to a power-of-two step below WT_REL
(WT) or RT_REL (RT, displacement and strain blocks apart) times its largest magnitude, and
compressed row by row, so a contact problem reads and decodes only the rows of the candidates that
carry force (`StoredCompliance` keeps each row it has read). A model is rounded when it is built,
before its first use: the run that builds it and every run that reads it use the same numbers, and
these differ from the factorised path's by less than STORED_RTOL of each quantity's largest
magnitude (docs/indentation.md, "Stored response models"). A contact problem, its deflections
and its receptor measures need no factorisation: the contact model of `contact_model` gives the
forces, deflections and observations of the factorised path (`fem.contact.linear.ContactModel.from_fe`)
within STORED_RTOL. Full displacement fields (a PVD) do need it.

    store = ResponseStore("out/cyl8")                      # <model>/response/<key>/
    key = response_key(model, approach, grid, store.mesh_sha256())
    rm = store.load(key) or store.save(build_response(model, approach, ReceptorSampler(model, grid), key))
    cm = contact_model(model, sn, {approach_key(approach): rm})   # fem.contact.linear.ContactModel
    responses, sampler, used = stored_responses(store, model, approaches, grid, touched)   # all of it

Files (docs/file-formats.md): WT.rows, RT.rows (`fem.io.rows.RowFile`, read by rows),
diagonal_mm_per_N.npy (k,), reach.npy (m,) bool, shift_mm.npy, lame_MPa.npy and response.json
(format, key, dimension, approach, shapes, receptor shifts, build seconds).
"""
from __future__ import annotations

import functools
import hashlib
import json
import logging
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from fem.contact.compliance import Compliance, DenseReach, RowCache
from fem.contact.facets import fe_facets
from fem.contact.linear import ContactModel
from fem.core import inverse
from fem.core.fields import STRAIN_COMPONENTS, hooke_matrix
from fem.core.system import coordinate_axis
from fem.io.modelfolder import CONDENSE_MAX_NODES, CONTACT_REGION, HELD, held_regions
from fem.io.rows import RowFile, quantise, write_rows
from fem.receptors.grid import ReceptorSampler, complete_outputs
from fingertip.progress import as_progress
from fingertip.staging import staged_output, write_json

logger = logging.getLogger(__name__)

RESPONSE_FORMAT = 4
"""Version of the stored layout and of what the key covers (raise it when either changes)."""
BLOCK = 64
"""Right-hand sides per solve when R and W are built."""
STORE_MAX_BYTES = 3 * 2**30
"""A model folder's response store keeps at most this many bytes: saving a model removes the
models used least recently (by their last load or save) until the rest fit."""
WT_REL = 1e-9
"""WT is stored rounded to a step below this fraction of each row's largest magnitude."""
INVERSE_ENTRIES_FROM_DOFS = 50_000
"""From this many unknowns a response model along a coordinate axis is built by MUMPS's entries of
the inverse where python-mumps is installed (`fem.core.inverse`): builds on the monkey 1.0 mm model
(70,629 unknowns) 4.7-5.7 s against 7.0-7.4 s by PARDISO, the human 0.5 mm whole `prepare` 141 s
against 191.5-214 s. Smaller models, where PARDISO takes a few seconds at most, were not compared."""
RT_REL = 5e-8
"""RT likewise, per row and block (the displacements, the strains)."""
STORED_RTOL = 1e-6
"""The error budget of a stored model: forces, deflections and receptor values differ from the
factorised path's by less than this fraction of each one's largest magnitude in the run (measured
up to 4.0e-7, the receptor SED of C5 to 3 mm on the human 0.5 mm model)."""


# --------------------------------------------------------------------------- key
def mesh_sha256(model_dir) -> str:
    """sha256 of a model folder's mesh.vtu bytes."""
    h = hashlib.sha256()
    with open(Path(model_dir) / "mesh.vtu", "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 22), b""):
            h.update(chunk)
    return h.hexdigest()


def approach_key(approach) -> tuple:
    """The approach (3,) rounded to 9 decimals: the same direction gives the same tuple."""
    a = np.asarray(approach, float)
    return tuple(float(v) for v in np.round(a / np.linalg.norm(a), 9) + 0.0)


def response_key(model, approach, grid, mesh_sha: str) -> str:
    """sha256 of everything a response model depends on: the mesh bytes (`mesh_sha256`), the
    material (code, moduli, nu per layer, rigid layers), the held regions, the approach (rounded,
    `approach_key`) and the receptor grid (points, depths, sites)."""
    mat = model.material
    spec = {"format": RESPONSE_FORMAT, "mesh": mesh_sha, "material": mat.code,
            "E_MPa": sorted((int(k), float(v)) for k, v in mat.E_MPa.items()),
            "nu": sorted((int(k), float(v)) for k, v in mat.nu.items()),
            "rigid": sorted(int(k) for k in mat.rigid),
            "held": repr(sorted((k, repr(v)) for k, v in HELD[model.dim].items() if k in model.regions)),
            "region": CONTACT_REGION[model.dim], "approach": approach_key(approach)}
    h = hashlib.sha256(json.dumps(spec, sort_keys=True).encode())
    for a in (np.round(grid.points_mm, 9) + 0.0, np.asarray(grid.depth_mm, float), np.asarray(grid.site, np.int64)):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


# --------------------------------------------------------------------------- the model
@dataclass
class ResponseModel:
    """WT (k, m) mm/N and RT (k, s) per N, one row per condensed candidate (module docstring),
    quantised: arrays when built (with their step exponents `exponents`, {"WT": (k, 1), "RT":
    (k, 2)}), `fem.io.rows.RowFile`s when read; the compliance's diagonal diagonal_mm_per_N (k,),
    reach (m,) bool (k True), approach (3,), receptor shifts shift_mm (n,) and Lame moduli
    lame_MPa (n, 2) (`ReceptorSampler.shift_mm`, `.lame_MPa`), the model's dimension, its key,
    build seconds and bytes on disk. The rows read so far stay with it (`row_cache`)."""
    key: str
    dim: int
    approach: np.ndarray
    reach: np.ndarray
    WT: np.ndarray | RowFile
    RT: np.ndarray | RowFile
    diagonal_mm_per_N: np.ndarray
    shift_mm: np.ndarray
    lame_MPa: np.ndarray
    build_seconds: float = float("nan")
    nbytes: int = 0
    exponents: dict | None = None
    _row_caches: dict = field(default_factory=dict, repr=False, compare=False)

    def row_cache(self, name: str) -> RowCache:
        """The rows of "WT" or "RT" read so far (`fem.contact.compliance.RowCache`), kept with the
        model: every contact problem it answers in this process reads and decodes a row once."""
        if name not in self._row_caches:
            rows = getattr(self, name)
            self._row_caches[name] = RowCache(lambda i: rows[i], *rows.shape)
        return self._row_caches[name]

    @property
    def blocks(self) -> dict:
        """{"WT": column blocks, "RT": column blocks} of the quantisation (`fem.io.rows`)."""
        return {"WT": [0, self.WT.shape[1]], "RT": [0, self.dim * len(self.shift_mm), self.RT.shape[1]]}

    def covers(self, candidates) -> bool:
        """Whether every candidate of the (m,) bool mask is condensed."""
        return len(candidates) == len(self.reach) and not np.any(np.asarray(candidates) & ~self.reach)


def build_response(model, approach, sampler, key: str, candidates=None, progress=None) -> ResponseModel:
    """The response model of a `fem.io.modelfolder.read_model` model along the unit `approach` (3,)
    for a `fem.receptors.grid.ReceptorSampler`: factorised held as `HELD` says with the condensed
    candidates (candidates: (m,) bool over the contact region's nodes, default all of them when
    there are at most CONDENSE_MAX_NODES) condensed along the approach. progress: optional
    `fingertip.progress` object (None: silent)."""
    t0 = time.perf_counter()
    sn = model.surface_nodes(CONTACT_REGION[model.dim])
    m = len(sn.nodes)
    candidates = np.ones(m, bool) if candidates is None else np.asarray(candidates, bool)
    if candidates.sum() > CONDENSE_MAX_NODES:
        raise ValueError(f"{int(candidates.sum())} contact candidates to condense: at most {CONDENSE_MAX_NODES}")
    a = np.asarray(approach, float)
    a = a / np.linalg.norm(a)
    if model.dim == 2 and abs(a[2]) > 1e-12:
        raise ValueError("a 2D model is indented within its x-y plane: the approach needs z = 0")
    progress = as_progress(progress)
    B = sp.csc_matrix((np.tile(a[:model.dim], m), (sn.dofs.ravel(), np.repeat(np.arange(m), model.dim))),
                      shape=(model.ndof, m))
    axis = coordinate_axis(a[:model.dim])
    if axis is not None and model.ndof >= INVERSE_ENTRIES_FROM_DOFS and inverse.available():
        reach, WT, RT = _by_inverse_entries(model, sn, candidates, a, axis, B, sampler, progress)
    else:
        reach, WT, RT = _by_schur_complement(model, sn, candidates, a, B, sampler, progress)
    k = int(reach.sum())
    rm = ResponseModel(key, model.dim, a, reach, WT, RT, np.zeros(k), np.asarray(sampler.shift_mm, float),
                       np.asarray(sampler.lame_MPa, float))
    rm.exponents = {"WT": quantise(WT, rm.blocks["WT"], WT_REL), "RT": quantise(RT, rm.blocks["RT"], RT_REL)}
    rm.diagonal_mm_per_N = WT[np.arange(k), np.flatnonzero(reach)]
    rm.build_seconds = time.perf_counter() - t0
    return rm


def _observed(reach, B, sampler) -> sp.csr_matrix:
    """(p, ndof) the outputs still to compute per condensed candidate: the displacement along the
    approach at the candidates not condensed (B's ~reach columns), then the sampler's independent
    receptor values."""
    return sp.vstack([B[:, ~reach].T, sampler.operator[:sampler.independent]]).tocsr()


def _by_schur_complement(model, sn, candidates, a, B, sampler, progress):
    """(reach (m,) bool, WT (k, m) [mm/N], RT (k, s)) of `build_response` by PARDISO: the compliance
    from the Schur complement onto the condensed candidates, the other outputs by backward
    substitutions (or through the transposed system when there are fewer outputs than candidates)."""
    with progress.task(f"response model: factorising {model.ndof} DOFs with {int(candidates.sum())} contact "
                       f"candidates condensed", kind=f"factorise-{model.dim}d",
                       size=model.ndof + 3 * int(candidates.sum())):
        system = model.system(held_regions(model), condense=(sn.nodes[candidates], a))
    reach = system.stored(sn.nodes, a)
    k, m = int(reach.sum()), len(reach)
    outputs = _observed(reach, B, sampler)
    with progress.task(f"response model: {min(k, outputs.shape[0])} solves for {outputs.shape[0] - (m - k)} "
                       f"receptor values and {m - k} other candidates"):
        if k <= outputs.shape[0]:                    # O K^-1 B: k loads on condensed unknowns
            out = _apply_condensed(system, sn.nodes[reach], a, outputs)
        else:                                        # B^T K^-1 O^T: one solve per row of O
            out = _apply_inverse(system, outputs.T.tocsc(), B[:, reach].T.tocsr())
    C = system.compliance(sn.nodes[reach], a)                       # symmetric: rows are columns
    del system
    model.release_factors()                 # the factorisation's memory (C stays): the rows are all it was for
    WT = np.empty((k, m))
    WT[:, reach], WT[:, ~reach] = C, out[:, :m - k]
    del C
    return reach, WT, np.ascontiguousarray(out[:, m - k:])


def _by_inverse_entries(model, sn, candidates, a, axis, B, sampler, progress):
    """`_by_schur_complement`'s (reach, WT, RT) by MUMPS (`fem.core.inverse`), for an approach along
    the coordinate `axis`: per block of neighbouring condensed candidates, the entries of K^-1 at the
    candidates and at the unknowns the outputs read, the load a unit force along `a` on the
    candidate's free DOF; the rows are written in place as each block arrives."""
    with progress.task(f"response model: factorising {model.ndof} DOFs (MUMPS)", kind=f"factorise-mumps-{model.dim}d",
                       size=model.ndof):
        free, upper = model.free_saddle(held_regions(model))
        entries = inverse.InverseEntries(upper)
        del upper
    along = sn.dofs[:, axis]
    reach = candidates & np.isin(along, free)
    k, m = int(reach.sum()), len(reach)
    outputs = _observed(reach, B, sampler)[:, free].tocsc()
    cols = np.searchsorted(free, along[reach])
    rows = np.union1d(np.flatnonzero(np.diff(outputs.indptr)), cols)
    read, at = outputs[:, rows].tocsr(), np.searchsorted(rows, cols)
    within, others = np.flatnonzero(reach), np.flatnonzero(~reach)
    WT, RT = np.empty((k, m)), np.empty((k, outputs.shape[0] - (m - k)))
    with progress.task(f"response model: entries of the inverse for {k} candidates at {len(rows)} unknowns"):
        for block in inverse.local_blocks(sn.x[reach], inverse.RHS_BLOCK):
            XT = entries.block_t(rows, cols[block])             # row j: K^-1 e_j, e_j the unknown along the axis
            WT[np.ix_(block, within)] = XT[:, at]               # a . u for u = a[axis] K^-1 e_j: a[axis]^2 = 1
            observed = a[axis] * (read @ XT.T).T
            WT[np.ix_(block, others)] = observed[:, :m - k]
            RT[block] = observed[:, m - k:]
    entries.release()
    return reach, WT, RT


def _apply_inverse(system, loads, observe) -> np.ndarray:
    """(p, q) observe (p, ndof) K^-1 loads (ndof, q) with a `fem.core.system.LinearSystem`, BLOCK
    columns per solve."""
    loads = sp.csc_matrix(loads)
    out = np.empty((observe.shape[0], loads.shape[1]))
    for s in range(0, loads.shape[1], BLOCK):
        u = system.solve(np.asfortranarray(loads[:, s:s + BLOCK].toarray()))
        out[:, s:s + BLOCK] = observe @ u
    return out


def _apply_condensed(system, nodes, a, observe) -> np.ndarray:
    """(k, p) (observe (p, ndof) K^-1 B)^T for unit loads along `a` at the condensed `nodes` (k,),
    BLOCK of them per backward substitution (`LinearSystem.solve_condensed`). The first block's
    residual is checked (and refined as `fem.core.linalg.SaddleFactor` does); later blocks only while
    refinement steps gained accuracy: the loads are all of one kind on one factorisation, so a
    block that needed none (or where refinement stopped helping) speaks for the rest."""
    out = np.empty((len(nodes), observe.shape[0]))
    check = True
    for s in range(0, len(nodes), BLOCK):
        out[s:s + BLOCK] = (observe @ system.solve_condensed(nodes[s:s + BLOCK], a, check=check)).T
        check = check and system.refined
    return out


# --------------------------------------------------------------------------- storage
class ResponseStore:
    """The response models of one model folder: `<model>/response/<key>/` with WT.rows, RT.rows,
    diagonal_mm_per_N.npy, reach.npy, shift_mm.npy, lame_MPa.npy and response.json; written
    atomically, read by rows. A model loaded or saved through a store object is held by it, with
    the rows read so far, for its later loads (the explorer's answers)."""

    ROWS = ("WT", "RT")
    ARRAYS = ("diagonal_mm_per_N", "reach", "shift_mm", "lame_MPa")

    def __init__(self, model_dir):
        self.folder = Path(model_dir) / "response"
        self._mesh_sha = self._memo = None
        self._held: dict[str, ResponseModel] = {}      # loaded or saved through this store, by key

    @classmethod
    def existing(cls, model_dir) -> ResponseStore | None:
        """The store of a model folder that already keeps response models, else None (for a model
        folder that cannot be written: it is read, never built)."""
        store = cls(model_dir)
        return store if store.folder.is_dir() else None

    def mesh_sha256(self) -> str:
        """`mesh_sha256` of the model folder, computed once and remembered in `response/mesh.json`
        with the file's size, inode and modification time: while those are unchanged the mesh is
        not read again (`pipeline.py mesh` writes a new file, so a new mesh has a new inode)."""
        if self._mesh_sha is None:
            st = (self.folder.parent / "mesh.vtu").stat()
            stamp = [st.st_size, st.st_ino, st.st_mtime_ns]
            memo = self.folder / "mesh.json"
            try:
                known = json.loads(memo.read_text())
                if known["stamp"] == stamp:
                    self._mesh_sha = str(known["sha256"])
            except (OSError, ValueError, KeyError, TypeError):
                pass
            if self._mesh_sha is None:
                self._mesh_sha = mesh_sha256(self.folder.parent)
                self._memo = {"stamp": stamp, "sha256": self._mesh_sha}
                self._remember()
        return self._mesh_sha

    def _remember(self) -> None:
        """Write `response/mesh.json` (see `mesh_sha256`) once the folder exists."""
        if self._memo is not None and self.folder.is_dir():
            try:
                write_json(self.folder / "mesh.json", self._memo)
                self._memo = None
            except OSError:
                pass                        # a read-only folder: the mesh is hashed again next time

    def path(self, key: str) -> Path:
        return self.folder / key

    def load(self, key: str) -> ResponseModel | None:
        """The stored model of `key` (its rows read when asked for); None when there is none. A
        folder that does not read back as written (missing or truncated file, other shapes) is
        removed with a warning, so the caller rebuilds it."""
        folder = self.path(key)
        if not folder.is_dir():
            self._held.pop(key, None)
            return None
        if key in self._held:
            self._touch(folder)
            return self._held[key]
        try:
            meta = json.loads((folder / "response.json").read_text())
            WT, RT = (RowFile(folder / f"{name}.rows") for name in self.ROWS)
            diagonal, reach, shift, lame = (np.load(folder / f"{name}.npy") for name in self.ARRAYS)
            k, m = meta["shape_WT"]
            n, dim = meta["receptor_points"], meta["dim"]
            ok = (meta["format"] == RESPONSE_FORMAT and meta["key"] == key and WT.shape == (k, m)
                  and list(RT.shape) == meta["shape_RT"] and RT.shape[0] == k
                  and RT.shape[1] == n * (dim + len(STRAIN_COMPONENTS[dim])) and diagonal.shape == (k,)
                  and reach.shape == (m,) and reach.dtype == bool and int(reach.sum()) == k
                  and shift.shape == (n,) and lame.shape == (n, 2))
            if not ok:
                raise ValueError("shapes or key differ from response.json")
        except (OSError, ValueError, KeyError, TypeError, EOFError) as exc:
            logger.warning(f"stored response model {folder} is unreadable ({exc}): removed, it will be rebuilt")
            shutil.rmtree(folder, ignore_errors=True)
            return None
        self._touch(folder)
        self._held[key] = ResponseModel(key, int(dim), np.asarray(meta["approach"], float), reach, WT, RT, diagonal,
                                        shift, lame, float(meta["build_seconds"]), int(meta["bytes"]))
        return self._held[key]

    @staticmethod
    def _touch(folder: Path) -> None:
        try:
            os.utime(folder / "response.json")          # its last use, for the store's size cap
        except OSError:
            pass                                        # a read-only store keeps no record

    def save(self, rm: ResponseModel) -> ResponseModel:
        """Write a built `rm` atomically (a staged folder renamed into place); returns it with
        `nbytes` set."""
        target = self.path(rm.key)
        with staged_output(target) as tmp:
            rm.nbytes = sum(write_rows(tmp / f"{name}.rows", getattr(rm, name), rm.exponents[name], rm.blocks[name])
                            for name in self.ROWS)
            for name in self.ARRAYS:
                np.save(tmp / f"{name}.npy", getattr(rm, name))
                rm.nbytes += (tmp / f"{name}.npy").stat().st_size
            write_json(tmp / "response.json", {
                "format": RESPONSE_FORMAT, "key": rm.key, "dim": rm.dim, "approach": np.asarray(rm.approach).tolist(),
                "shape_WT": list(rm.WT.shape), "shape_RT": list(rm.RT.shape),
                "receptor_points": len(rm.shift_mm), "build_seconds": rm.build_seconds, "bytes": rm.nbytes})
        self._remember()
        self._held[rm.key] = rm
        self._evict(keep=rm.key)
        return rm

    def _evict(self, keep: str) -> None:
        """Remove the models used least recently (response.json's modification time, which `load`
        touches) but `keep` until the store holds at most STORE_MAX_BYTES."""
        models = []
        for folder in self.folder.iterdir():
            try:
                meta = folder / "response.json"
                models.append((meta.stat().st_mtime_ns, folder.name, int(json.loads(meta.read_text())["bytes"])))
            except (OSError, ValueError, KeyError, TypeError):
                continue
        total = sum(size for _, _, size in models)
        for _, key, size in sorted(models):
            if total <= STORE_MAX_BYTES:
                break
            if key != keep:
                logger.warning(f"response store of {self.folder.parent} over {STORE_MAX_BYTES / 2**30:g} GiB: "
                               f"removing the model used least recently ({key[:12]}, {size / 2**20:.0f} MB)")
                shutil.rmtree(self.path(key), ignore_errors=True)
                self._held.pop(key, None)
                total -= size


# --------------------------------------------------------------------------- contact
class StoredCompliance(DenseReach, Compliance):
    """The compliance and observed response of a `ResponseModel`: the same interface as
    `fem.contact.compliance.CondensedCompliance` (NaN compliance rows outside `reach`, deflections of
    those candidates with the observation), answered by matrix products, no solves. Only the
    rows of candidates a contact problem touches are read from the model (decoded from its row
    files when stored), each once. Observed responses are completed with their stress rows
    (`complete_outputs`)."""

    def __init__(self, rm: ResponseModel):
        m = rm.WT.shape[1]
        hooke = hooke_matrix(*np.asarray(rm.lame_MPa).T, rm.dim)       # (stress rows, strain rows)
        super().__init__(m, rm.RT.shape[1] + hooke.shape[0])
        self._complete = functools.partial(complete_outputs, hooke=hooke)
        self._read, self._read_RT = rm.row_cache("WT"), rm.row_cache("RT")     # rows read so far
        self._dense(rm.reach, rm.diagonal_mm_per_N)

    def _rows(self, rows) -> np.ndarray:
        slots = self._read.slots(rows)
        w = self._read.data[slots]
        return w if self.reach.all() else w[:, self.reach]

    def block(self, rows, cols) -> np.ndarray:
        """(len(rows), len(cols)) compliance between candidates (WT's columns are all m of them):
        only those entries are gathered."""
        slots = self._read.slots(self._row[np.asarray(cols, int)])
        return self._read.data[np.ix_(slots, np.asarray(rows, int))].T

    def observed(self, idx) -> np.ndarray:
        slots = self._read_RT.slots(self._row[np.asarray(idx, int)])
        return self._complete(self._read_RT.data[slots].T)

    def response(self, force_N) -> tuple[np.ndarray, np.ndarray]:
        """((m, k) deflections of every candidate along the approach, (r, k) observed response) to
        nodal contact forces (m, k): the rows of the candidates that carry force only."""
        F = np.asarray(force_N, float).reshape(self.m, -1)[self.reach]
        act = np.flatnonzero(np.any(F != 0, axis=1))
        slots, slots_RT = self._read.slots(act), self._read_RT.slots(act)
        return self._read.data[slots].T @ F[act], self._complete(self._read_RT.data[slots_RT].T @ F[act])

    def observe(self, force_N) -> np.ndarray:
        """(r,) or (r, k) observed response to nodal contact forces (m,) or (m, k)."""
        return self.response(force_N)[1].reshape((self.r,) + np.shape(force_N)[1:])

    def displacement(self, force_N):
        raise ValueError("a stored response model has no full displacement field: factorise the model")


def contact_model(model, sn, responses: dict) -> ContactModel:
    """ContactModel on the contact region's candidates `sn` of a model (the candidates, areas and
    facets of `ContactModel.from_fe`) answered by stored response models {approach_key: model}."""
    def compliance_for(a):
        rm = responses.get(approach_key(a))
        if rm is None:
            raise ValueError(f"no response model along {np.round(a, 6).tolist()}")
        return StoredCompliance(rm)
    return ContactModel(sn.x, sn.area, compliance_for, facets=fe_facets(model, CONTACT_REGION[model.dim], sn))


def stored_responses(store: ResponseStore, model, approaches, grid, touched, progress=None):
    """({approach_key: ResponseModel}, ReceptorSampler, [(key, "stored" or "built", seconds, bytes)])
    for the approaches (each (3,)) of a scene on a `read_model` model with receptor grid `grid`:
    each read from `store` when stored and its condensed candidates cover `touched` ((m,) bool,
    e.g. `fem.contact.linear.reach` of the scene, or all candidates), else built with the touched
    candidates and those stored before condensed (the touched ones alone when together they
    exceed CONDENSE_MAX_NODES) and stored. The build time grows with the condensed candidates
    (one solve each), so a scene condenses what it can touch and `pipeline.py prepare` all.
    A store that cannot be written is warned about; the models built are used all the same.
    The sampler has an operator only when something was built."""
    progress = as_progress(progress)
    out, used, sampler, mesh_sha = {}, [], None, store.mesh_sha256()
    for a in approaches:
        ak = approach_key(a)
        if ak in out:
            continue
        key = response_key(model, a, grid, mesh_sha)
        rm = store.load(key)
        if rm is None or not rm.covers(touched):
            candidates = touched | (rm.reach if rm is not None else False)
            if candidates.sum() > CONDENSE_MAX_NODES:
                candidates = touched
            if sampler is None:
                with progress.task(f"receptor operators at {len(grid.points_mm)} points",
                                   kind=f"sampler-{model.dim}d", size=len(grid.points_mm)):
                    sampler = ReceptorSampler(model, grid)
            rm = build_response(model, a, sampler, key, candidates, progress)
            try:
                store.save(rm)
            except OSError as exc:
                logger.warning(f"cannot store the response model in {store.folder} ({exc}): the next run "
                               f"factorises again")
            used.append((key, "built", rm.build_seconds, rm.nbytes))
        else:
            used.append((key, "stored", rm.build_seconds, rm.nbytes))
        out[ak] = rm
    if sampler is None:
        sampler = ReceptorSampler.without_operator(model.dim, grid, next(iter(out.values())).shift_mm)
    return out, sampler, used
