"""The free-arc volute fit and the choice of model by an information criterion.

``free_arcs`` starts from the fitted ``centred_arcs`` volute as a tangent arc chain
(:mod:`~ionic_usd.evaluate.volute_chain`) and frees every quarter-turn arc's radius (the
centres follow from tangency), fitted by least squares on the reference's nodes;
``free_joints`` then frees the joints too (each arc's sweep: a carver's centre off the
square moves the joint). The centred
chain is refitted by least squares the same way, so both are judged on the same residuals;
the log spiral's residuals are its fitted curve's distances to the nodes. Every model gets
AIC and BIC (``n·ln(RSS/n) + 2k`` / ``+ k·ln n``, ``k`` the free parameters with the pose) and
the lowest BIC is chosen: more arcs win only where the data support them.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from scipy.spatial import cKDTree

from ionic_usd.column.column import ColumnParams
from ionic_usd.errors import GeometryError, ParameterError
from ionic_usd.evaluate.fit_core import FitResult, compare_aligned, densify
from ionic_usd.evaluate.volute_chain import (
    ArcChain,
    chain_from_centred,
    criterion,
    fit_chain,
    free_parameters,
    volute_from_chain,
)

__all__ = ["CHAIN_MODELS", "CRITERION", "add_free_arcs", "choose_by_criterion"]

#: The criterion that chooses the model (``aic`` and ``bic`` are both reported).
CRITERION = "bic"

#: The arc-chain models fitted from the centred arcs, each starting from the one before.
CHAIN_MODELS = ("free_arcs", "free_joints")

#: Free parameters of the Hausdorff-fitted models (shape and start/turns, translation).
_LOG_SPIRAL_K = 7


def _size(ref: np.ndarray) -> float:
    return float(np.linalg.norm(np.ptp(ref, axis=0)))


def _rss_to_curve(ref: np.ndarray, curve: np.ndarray, h: float) -> float:
    d, _ = cKDTree(densify(curve, h / 8.0)).query(ref)
    return float(np.sum(d**2))


def add_free_arcs(
    results: list[FitResult],
    *,
    chains: tuple[str, ...] = CHAIN_MODELS,
    keep_centred: bool = True,
) -> list[FitResult]:
    """Give every result its criterion values and append the ``chains`` fits (from the
    ``centred_arcs`` result); ``keep_centred=False`` drops the centred result (not asked for)."""
    out = []
    for r in results:
        if r.model == "centred_arcs":
            out.extend(_chains_from(r, chains=chains, keep_centred=keep_centred))
        else:
            n = len(r.reference)
            rss = _rss_to_curve(r.reference, r.fitted, r.spacing)
            crit = criterion(rss, n, _LOG_SPIRAL_K, _size(r.reference))
            out.append(dataclasses.replace(r, criterion=crit))
    return out


_FREED = {
    "free_arcs": "every arc's radius free",
    "free_joints": "every arc's radius and every joint (the arcs' sweeps) free",
}


def _chains_from(r: FitResult, *, chains: tuple[str, ...], keep_centred: bool) -> list[FitResult]:
    ref, n = r.reference, len(r.reference)
    start = chain_from_centred(
        r.params,  # type: ignore[arg-type]
        r.alignment.mirrored,
        (r.values["translation_x"], r.values["translation_y"]),
    )
    if n < 2 * free_parameters(start, "centred_arcs"):  # too few nodes to refit anything
        rss = _rss_to_curve(ref, r.fitted, r.spacing)
        note = f"free arc models not fitted: {n} nodes are too few"
        crit = criterion(rss, n, free_parameters(start, "centred_arcs"), _size(ref))
        return [dataclasses.replace(r, criterion=crit, notes=(*r.notes, note))]
    centred, rss_c, k_c = fit_chain(start, ref, "centred_arcs")
    res = []
    if keep_centred or not chains:
        rms = np.sqrt(rss_c / n)
        note = f"criterion on the least-squares refit of the centred arcs (rms {rms:.3g} m)"
        crit = criterion(rss_c, n, k_c, _size(ref))
        res.append(dataclasses.replace(r, criterion=crit, notes=(*r.notes, note)))
    chain = centred
    for model in CHAIN_MODELS:  # each from the one before: centred, free radii, free joints
        if not any(CHAIN_MODELS.index(c) >= CHAIN_MODELS.index(model) for c in chains):
            break
        if n < 2 * free_parameters(chain, model):  # the data cannot support it
            break
        t0 = time.perf_counter()
        chain, rss, k = fit_chain(chain, ref, model)
        if model in chains:
            res.append(_chain_result(r, model, chain, rss, k, rss_c, time.perf_counter() - t0))
    return res


def _chain_result(
    r: FitResult, model: str, chain: ArcChain, rss: float, k: int, rss_c: float, seconds: float
) -> FitResult:
    ref, n = r.reference, len(r.reference)
    after, al, fit_al = compare_aligned(
        ref, chain.points(), allow_mirror=False, max_segment=r.spacing
    )
    values = {f"radius_{j}": float(v) for j, v in enumerate(chain.radii)}
    if model == "free_joints":
        values.update({f"sweep_{j}_deg": float(np.degrees(v)) for j, v in enumerate(chain.sweeps)})
    values.update(
        first_centre_x=chain.c0[0],
        first_centre_y=chain.c0[1],
        start_direction_deg=float(np.degrees(chain.phi0)),
        last_sweep_deg=float(np.degrees(chain.sweeps[-1])),
        mirrored=float(chain.sense < 0),
    )
    params, column, rebuilt = _rebuilt(r, chain)
    notes = (
        f"{_FREED[model]} ({len(chain.radii)} arcs), centres from tangency, first centre, "
        "start direction and last sweep fitted by least squares from the centred-arc fit",
        f"rms {np.sqrt(rss / n):.3g} m against {np.sqrt(rss_c / n):.3g} m for the centred arcs",
        rebuilt,
    )
    return dataclasses.replace(
        r,
        params=params,
        column=column,
        before=r.after,
        after=after,
        fitted=fit_al,
        initial=r.fitted,
        alignment=al,
        notes=notes,
        model=model,
        bounds_hit=(),
        values=values,
        seconds=seconds,
        criterion=criterion(rss, n, k, _size(ref)),
        alternatives=(),
    )


def _rebuilt(r: FitResult, chain: ArcChain) -> tuple[object, ColumnParams, str]:
    """The fitted chain as the column's volute (``arc_radii``/``arc_sweeps`` of the centred-arc
    model), with the note saying so; the centred-arc volute where the chain makes none."""
    try:
        volute = volute_from_chain(
            chain,
            r.params,  # type: ignore[arg-type]
            r.alignment.mirrored,
            (r.values["translation_x"], r.values["translation_y"]),
        )
    except (ParameterError, GeometryError, ValueError) as err:
        why = str(err).splitlines()[0]
        return r.params, r.column, f"the column keeps the centred-arc volute: the chain {why}"
    column = dataclasses.replace(r.column, capital=r.column.capital.with_(volute=volute))
    return volute, column, "the column is rebuilt with this chain (arc_radii, arc_sweeps)"


def choose_by_criterion(results: list[FitResult]) -> list[FitResult]:
    """The results by increasing :data:`CRITERION` (the chosen model first)."""
    return sorted(results, key=lambda r: r.criterion.get(CRITERION, np.inf))
