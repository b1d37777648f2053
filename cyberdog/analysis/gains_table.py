"""The gains table: the battery saving against the cheaper common trajectory with the drivers' kp or kd alone
scaled, as commanded and re-commanded, beside the default gains' (`tools/merge_walks.py gains`'s walks); where a
run walked the searched shape under its gains too, that shape's saving and the learned paths' lead over it."""
from __future__ import annotations

from cyberdog.analysis import prototype_summary as ps
from cyberdog.analysis.markdown_cells import header as _header
from cyberdog.analysis.markdown_cells import line as _line
from cyberdog.analysis.markdown_cells import mean_ci, missed_walks

GAINS_DEFAULT_ROW = "default gains (kp 60, kd 2)"  # the gains table's first row: the prototype table's saving
POLICY_ROW = "the policy, closed loop"  # the gains table's rows of the policies walking the protocol themselves
GAINS_DEFAULT_POLICY_ROW = f"default gains, {POLICY_ROW}"
SEARCHED = "the searched shape"  # the prototype run's default reference, as the gains rows name it


def reference_labels(reference: str) -> tuple[str, str]:
    """The labels of the rows after a gain's as-commanded row where its run walked the prototype's reference too
    (`reference`: what that reference is): its own saving, and the learned paths' lead over it."""
    return f"{reference}'s saving", f"learned against {reference}"


SEARCHED_SAVING, VS_SEARCHED = reference_labels(SEARCHED)


def saving_cells(walks: list[dict], trajectory: str, robot: str, speeds: list[float]) -> list[str] | None:
    """The battery saving of `trajectory`'s walks at each speed (with the walks that did not count), None if it
    has none."""
    by = {r["speed_mps"]: r for r in ps.summary_rows(walks) if r["robot"] == robot and r["trajectory"] == trajectory}
    if not by:
        return None
    return ["–" if v not in by else mean_ci(by[v], "battery_saving_pct", ".1f", " %") + missed_walks(by[v])
            for v in speeds]


def reference_rows(walks: list[dict], robot: str, speeds: list[float], reference: str = SEARCHED
                   ) -> list[tuple[str, list[str]]]:
    """The reference's own saving and the learned paths' against it (`reference_labels(reference)`), where the
    walks hold the prototype run's reference row (`ps.REFERENCE`, walked under the same gains)."""
    rows = {(r["trajectory"], r["speed_mps"]): r for r in ps.summary_rows(walks) if r["robot"] == robot}
    if not any(t == ps.REFERENCE for t, _ in rows):
        return []
    searched = saving_cells(walks, ps.REFERENCE, robot, speeds) or []
    vs = ["–" if ("learned", v) not in rows else mean_ci(rows["learned", v], "battery_vs_searched_pct", ".1f", " %",
                                                         sign=True) for v in speeds]
    return list(zip(reference_labels(reference), (searched, vs)))


def _speeds(default_walks: list[dict], robot: str) -> list[float]:
    return sorted({w["speed_mps"] for w in default_walks if w["robot"] == robot and w["trajectory"] == "learned"})


def gains_rows(walks: list[dict], default_walks: list[dict], robot: str = "hardware", reference: str = SEARCHED
               ) -> list[tuple[str, list[str]]]:
    """(label, cells) per gain and factor (kp first), as commanded (then, where the run walked the prototype's
    reference, named `reference`, its rows), re-commanded (bold), then the policies' own where the run walked
    them: the rows after the default gains' (`gains_markdown`)."""
    speeds = _speeds(default_walks, robot)
    rows = []
    factors = sorted({(w["gain"], w["gain_scale"]) for w in walks}, key=lambda f: (f[0] != "kp", f[1]))  # kp first
    for gain, scale in factors:
        at = [w for w in walks if (w["gain"], w["gain_scale"]) == (gain, scale)]
        for matched in (False, True):  # as commanded, then re-commanded
            cells = saving_cells([w for w in at if bool(w["pd_matched"]) == matched], "learned", robot, speeds)
            if cells is not None:
                label = f"{gain} {scale:g}×, {'re-commanded' if matched else 'as commanded'}"
                rows.append((f"**{label}**", [f"**{c}**" for c in cells]) if matched else (label, cells))
            if not matched:  # where the run walked the searched shape under the same gains: both against it
                rows += [(f"{gain} {scale:g}×, as commanded: {label}", cells)
                         for label, cells in reference_rows([w for w in at if not w["pd_matched"]], robot, speeds,
                                                            reference)]
        # the policies against the common trajectories as commanded
        policy = saving_cells([w for w in at if not w["pd_matched"]], "policy", robot, speeds)
        if policy:
            rows.append((f"{gain} {scale:g}×, {POLICY_ROW}", policy))
    return rows


def gains_markdown(walks: list[dict], default_walks: list[dict], robot: str = "hardware",
                   default_policy_walks: list[dict] | None = None) -> str:
    """The gains table: the battery saving against the cheaper common trajectory with the drivers' kp or kd alone
    scaled (`tools/merge_walks.py gains`'s walks, each labelled `gain`, `gain_scale`, `pd_matched`), as commanded and
    re-commanded, beside the default gains' (the prototype run's `default_walks`). Where a run walked the
    policies too (`prototype --closed-loop`), their row follows that factor's: the policy itself under those
    gains, nothing re-solved; `default_policy_walks` (walks at the default gains with the policies among them,
    e.g. the stiffness run's PD 1× walks) give the default gains' policy row."""
    speeds = _speeds(default_walks, robot)
    default = {r["speed_mps"]: r for r in ps.summary_rows(default_walks)
               if r["robot"] == robot and r["trajectory"] == "learned"}
    lines = _header("battery saving against the cheaper common trajectory", speeds)
    lines.append(_line(GAINS_DEFAULT_ROW, [mean_ci(default[v], "battery_saving_pct", ".1f", " %") for v in speeds]))
    policy = saving_cells(default_policy_walks or [], "policy", robot, speeds)
    if policy:
        lines.append(_line(GAINS_DEFAULT_POLICY_ROW, policy))
    lines += [_line(label, cells) for label, cells in gains_rows(walks, default_walks, robot)]
    return "\n".join(lines)
