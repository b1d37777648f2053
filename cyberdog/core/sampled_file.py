"""The file of a sampled foot trajectory (`trajectories.SampledTrajectory`): JSON, or CSV by a ".csv" suffix.

Both hold the same fields, the dict `SampledTrajectory.to_dict` gives: the recorded step length and lift height (m),
the points over one gait cycle (phase, x_m, z_m; phase 0 = lift-off, x and z from the neutral point), the foot inset
(m, only where it is not zero) and the provenance (a JSON object). The CSV keeps the scalars and the provenance in
"# key: value" header lines and writes the points with `repr`, so a float goes through a file and back unchanged.
Files are written atomically (a temporary file beside, then a rename). Pure Python.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

FORMAT = "cyberdog.sampled_foot_trajectory"
VERSION = 1
CSV_TITLE = "# cyberdog sampled foot trajectory: phase 0 = lift-off; x, z in m from the neutral point"
CSV_COLUMNS = "phase,x_m,z_m"


def is_csv(path: Path) -> bool:
    return path.suffix.lower() == ".csv"


def write(path: str | Path, fields: dict) -> Path:
    """Write `fields` (`SampledTrajectory.to_dict`'s) to `path`, CSV for a ".csv" suffix, else JSON; returns it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if is_csv(path):
        inset = fields.get("foot_inset_m", 0.0)
        lines = [CSV_TITLE, f"# step_length_m: {fields['step_length_m']!r}",
                 f"# lift_height_m: {fields['lift_height_m']!r}", *([f"# foot_inset_m: {inset!r}"] if inset else []),
                 f"# provenance: {json.dumps(fields['provenance'])}", CSV_COLUMNS]
        lines += [f"{p!r},{x!r},{z!r}" for p, x, z in zip(fields["phase"], fields["x_m"], fields["z_m"])]
        text = "\n".join(lines) + "\n"
    else:
        text = json.dumps(fields, indent=1)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)
    return path


def read(path: str | Path) -> dict:
    """The fields of a file `write` wrote (JSON, or CSV by its ".csv" suffix); ValueError if it is missing or a CSV
    lacks the step length or lift height."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"sampled trajectory file {str(path)!r} does not exist")
    if not is_csv(path):
        return json.loads(path.read_text())
    meta: dict[str, str] = {}
    rows = []
    for line in path.read_text().splitlines():
        if line.startswith("#"):
            key, sep, value = line[1:].partition(":")
            if sep:
                meta[key.strip()] = value.strip()
        elif line.strip() and not line.startswith("phase"):
            row = line.split(",")
            if len(row) != 3:
                raise ValueError(f"CSV {str(path)!r}: a point is phase,x_m,z_m, got {line!r}")
            rows.append([float(v) for v in row])
    missing = {"step_length_m", "lift_height_m"} - set(meta)
    if missing:
        raise ValueError(f"CSV {str(path)!r} lacks header line(s) {sorted(missing)}")
    return {"step_length_m": float(meta["step_length_m"]), "lift_height_m": float(meta["lift_height_m"]),
            "phase": [r[0] for r in rows], "x_m": [r[1] for r in rows], "z_m": [r[2] for r in rows],
            "foot_inset_m": float(meta.get("foot_inset_m", 0.0)), "provenance": json.loads(meta.get("provenance", "{}"))}
