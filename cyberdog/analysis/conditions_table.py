"""The rows of a searched-start recipe's paths walked on a robot or a floor other than the prototype run's (a payload
the body carries, the floor's friction): what a user changes beyond the ranges the recipe trained over (mass scale
0.9–1.15, floor friction 0.56–1.04). Each run is the recipe's inset step (the prototype run against the shape
searched for the battery with a narrower stance) with one setting of `CONDITIONS` changed; `tools/merge_walks.py
conditions` labels its walks with `condition` (the setting) and `condition_value`.

Per condition: the learned paths' battery saving against the cheaper common trajectory (the walks off the band or
fallen named), the narrower-stance shape's own saving under it, and the paths' lead over that shape."""
from __future__ import annotations

from cyberdog.analysis.gains_table import reference_rows, saving_cells

# the settings a conditions run may change (`--set SETTING=VALUE`), each with how a row names its value
CONDITIONS = {"robot.payload": "a {:g} kg payload", "sim.ground_friction": "floor friction {:g}"}
INSET_SHAPE = "the shape searched for the battery with a narrower stance"  # the runs' reference, as rows name it


def condition_label(setting: str, value: float) -> str:
    """"a 3 kg payload": how a row names a conditions run; ValueError for a setting not in `CONDITIONS`."""
    if setting not in CONDITIONS:
        raise ValueError(f"{setting!r} is not a condition of the table (one of {', '.join(CONDITIONS)})")
    return CONDITIONS[setting].format(value)


def conditions_of(walks: list[dict]) -> list[tuple[str, float]]:
    """The (setting, value) runs the walks hold, in `CONDITIONS`' order and then by value; ValueError for a setting
    not in `CONDITIONS`."""
    runs = {(w["condition"], w["condition_value"]) for w in walks}
    for setting, value in runs:
        condition_label(setting, value)
    return sorted(runs, key=lambda c: (list(CONDITIONS).index(c[0]), c[1]))


def conditions_rows(walks: list[dict], speeds: list[float], robot: str = "hardware"
                    ) -> list[tuple[str, list[str]]]:
    """(label, cells) per condition (`conditions_of`' order): the paths' saving with it ("with a 3 kg payload"),
    then the reference's saving and the paths' lead over it where the run walked the reference (`INSET_SHAPE`)."""
    rows = []
    for setting, value in conditions_of(walks):
        label = condition_label(setting, value)
        at = [w for w in walks if (w["condition"], w["condition_value"]) == (setting, value)]
        cells = saving_cells(at, "learned", robot, speeds)
        if cells is not None:
            rows.append((f"the saving with {label}", cells))
        rows += [(f"{label}: {name}", cells) for name, cells in reference_rows(at, robot, speeds, INSET_SHAPE)]
    return rows
