"""The thesis's depth-dependent claims judged with both kinematics: which kinematics the thesis
itself used for each (its words, quoted with their section), the claims run again with finite
kinematics (`fem.contact.finite`: neo-Hookean, frictionless contact measured in the deformed
configuration) where that solver models them, and, per linear finding, the finite finding's verdict
beside it with the checks whose outcome differs, or the reason the finite run was not made (the
solver's own refusal, or its measured cost).

`finite_claims` is the claim `pipeline.py reproduce` runs for it (fem.thesis.claims); `side_by_side`
makes the report's table from all findings. The finite runs use the same models, mesh levels and
loads as the linear ones (figure 4-24's forces F* and F*/10 are the linear model's), so the two
columns differ by the kinematics alone.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from fem.contact.surfaces import check_modelled
from fem.core.neohookean import NO_FLUID_CORE
from fem.thesis.chapter4_mechanics import cylinder_runs, depth_findings
from fem.thesis.findings import Finding, Workshop, number
from fingertip.errors import InputError

FINITE = "_finite"
"""Key suffix of a finding run with finite kinematics (its linear twin: the key without it)."""


@dataclass(frozen=True)
class ThesisKinematics:
    """What the thesis says of the kinematics behind a claim: used ('small deformation', 'large
    displacement' or 'not stated'), its words and their section."""
    used: str
    words: str
    section: str


SMALL_2D = ThesisKinematics(
    "small deformation", "due the singular nature of the concentrated load coupled with the plane strain and small "
    "deformation assumptions", "4.7")
LINE_LOAD_3D = ThesisKinematics(
    "large displacement", "The finite element problem was solved using the large displacement formulation.", "6.2.1")
CONTACT_3D = ThesisKinematics(
    "not stated", "The finite element models used in the simulations have a linear material model", "6.2.3")

#: Finding key prefix of each depth-dependent claim -> the thesis's kinematics for it.
THESIS_KINEMATICS = {"fig4-24": SMALL_2D, "fig4-25": SMALL_2D, "fig6-10": LINE_LOAD_3D,
                     "sec6-2-1_dorsal": LINE_LOAD_3D, "fig5-14": CONTACT_3D, "fig6-30": CONTACT_3D,
                     "fig7-2": CONTACT_3D, "fig7-3": CONTACT_3D}


def _refusal(check) -> str:
    """The InputError message check() raises (the finite solver's refusal), '' when it runs."""
    try:
        check()
    except InputError as exc:
        return str(exc)
    return ""


def not_run_reasons() -> dict[str, str]:
    """Finding key prefix -> why reproduce has no finite run of it: the solver's own refusal
    (fluid core, wedge), or the cost of a 3D finite contact run (docs/indentation.md)."""
    wedge = _refusal(lambda: check_modelled("wedge"))
    cost = ("not run by reproduce: a 3D finite indentation takes minutes "
            "(benchmarks/finite_contact.py); run it with `indent ... --kinematics finite`")
    return {"fig4-24_solid_fluid": NO_FLUID_CORE, "fig4-25": NO_FLUID_CORE + " (the checks compare it with the solid "
            "model)", "fig6-10": wedge, "sec6-2-1_dorsal": wedge, "fig5-14": cost, "fig6-30": cost,
            "fig7-2": cost, "fig7-3": cost}


def as_finite(f: Finding) -> Finding:
    """A finding of finite-kinematics runs: its key with FINITE, its title saying so."""
    return replace(f, key=f.key + FINITE, title=f.title + " (finite kinematics)", kinematics="finite")


def finite_claims(shop: Workshop) -> list[Finding]:
    """Figure 4-24's depth law (both readings) on the solid 2D cylinders with finite kinematics, at
    the linear run's forces."""
    return [as_finite(f) for f in depth_findings(cylinder_runs(shop, "finite"))]


def _prefix(key: str, table) -> str | None:
    return next((p for p in table if key.startswith(p)), None)


def side_by_side(findings: list[Finding]) -> list[dict]:
    """One row per linear finding of a depth-dependent claim (THESIS_KINEMATICS): key, section,
    title, the thesis's kinematics, the linear and finite verdicts and why: each check's value with
    both kinematics and whether its outcome changed, or ('not run') why there is no finite twin."""
    by_key = {f.key: f for f in findings}
    reasons = not_run_reasons()
    rows = []
    for f in findings:
        used = THESIS_KINEMATICS.get(_prefix(f.key, THESIS_KINEMATICS))
        if f.kinematics != "linear" or used is None:
            continue
        twin = by_key.get(f.key + FINITE)
        row = {"key": f.key, "section": f.section, "title": f.title, "thesis_kinematics": used.used,
               "thesis_words": f"'{used.words}' ({used.section})", "linear": f.verdict}
        if twin is None:
            row.update(finite="not run", why=reasons[_prefix(f.key, reasons)])
        else:
            row.update(finite=twin.verdict, why="; ".join(
                f"{a.what}: linear {number(a.value, 4)}, finite {number(b.value, 4)}{a.unit and ' ' + a.unit} "
                + (f"({a.outcome} -> {b.outcome})" if a.outcome != b.outcome else f"(both {a.outcome})")
                for a, b in zip(f.checks, twin.checks)))
        rows.append(row)
    return rows
