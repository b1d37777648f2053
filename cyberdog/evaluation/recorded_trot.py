"""The trot controller a comparison walks under.

A learned path is the shift of the trot controller's foot targets that a policy commanded under one trot
(`ControllerConfig`: foot placement, the speed loop's bound, ...), and extraction writes that trot into the
path's provenance (`LearnedPath.recorded_controller`). The path and its trot are one gait: walked under another
trot, a path need not save what it saved. So by default an evaluation walks every trajectory of a comparison,
the learned paths, the common trajectories and the searched shape alike, under the trot the learned paths were
recorded under, and says so; the comparison stays at matched conditions, because every row walks the same trot.
A user who sets the trot (`--set controller.FIELD=VALUE`, a `controller:` section in `--config`) or asks for the
config's own (`--no-recorded-trot`) gets it, and a note for every path recorded under another. A searched shape
(the reference row) records the trot it was searched under (`--set controller.*` of tools/optimize_trajectory.py);
walked under another, a note says so: a shape searched for one trot is a weaker reference under another.
"""
from __future__ import annotations

import dataclasses

from cyberdog import config as C
from cyberdog.core.learned_set import LearnedSet


def controller_note(recorded: C.ControllerConfig | dict | None, walked: C.ControllerConfig) -> str:
    """Where the trot controller `walked` differs from `recorded` (a path's, a policy's), as a sentence with the
    `--set` that walks under the recorded one; "" where they agree or nothing was recorded."""
    if recorded is None:
        return ""
    diff = _differences(recorded, walked)
    if not diff:
        return ""
    what = ", ".join(f"{k} {r:g} recorded, {w:g} here" if isinstance(r, (int, float)) and not isinstance(r, bool)
                     else f"{k} {r} recorded, {w} here" for k, (r, w) in diff.items())
    return f"{what} (--set {_assignments(diff)} walks every trajectory under the recorded one)"


def note_controllers(learned: LearnedSet, cfg: C.WalkConfig, log=print) -> list[str]:
    """Log, and return, one note per learned path recorded under another trot controller than `cfg`'s (e.g. a
    policy trained with sagittal foot placement, walked here without it): its saving may not carry over."""
    notes = []
    for p in learned.paths():
        note = controller_note(p.recorded_controller, cfg.controller)
        if note:
            notes.append(f"note: {p.label}'s path ({p.file_name()}) was recorded under another trot controller: "
                         f"{note}")
            log(notes[-1])
    return notes


def user_sets_trot(args) -> bool:
    """Whether the command line chose the trot: --no-recorded-trot, a --set controller.FIELD=VALUE, or a
    --config file with a `controller` section."""
    if getattr(args, "no_recorded_trot", False):
        return True
    if any(str(item).split("=", 1)[0].strip().startswith("controller.") for item in getattr(args, "overrides", [])):
        return True
    path = getattr(args, "config", None)
    if path is None:
        return False
    import yaml

    try:
        data = yaml.safe_load(path.read_text()) or {}
    except (OSError, yaml.YAMLError):
        return False  # the config's own loading reports it
    return isinstance(data, dict) and "controller" in data


def recorded_trot(learned: LearnedSet) -> dict | None:
    """The trot controller every path of `learned` was recorded under; None where a path records none or two
    paths record different ones (each is then walked as configured, with a note)."""
    records = [p.recorded_controller for p in learned.paths()]
    if not records or any(r is None for r in records):
        return None
    first = records[0]
    return dict(first) if all(r == first for r in records[1:]) else None


def with_trot(cfg: C.WalkConfig, recorded: dict) -> C.WalkConfig:
    """`cfg` with its trot controller's fields set to `recorded`'s (fields the record lacks keep `cfg`'s; fields
    `ControllerConfig` lacks are ignored)."""
    names = {f.name for f in dataclasses.fields(C.ControllerConfig)}
    changes = {k: v for k, v in recorded.items() if k in names}
    return dataclasses.replace(cfg, controller=dataclasses.replace(cfg.controller, **changes))


def trot_for(args, cfg: C.WalkConfig, recorded: C.ControllerConfig | dict | None, what: str, log=print,
             walked: str = "every trajectory walks under it here") -> C.WalkConfig:
    """The walk config to walk `what` (a learned set, a policy) under: `cfg` with the `recorded` trot, unless the
    command line chose the trot or nothing was recorded. Logs the change, or the note where the user's trot
    differs from the recorded one (`walked`: what walks under it, in the log's words)."""
    if recorded is None:
        return cfg
    record = recorded if isinstance(recorded, dict) else dataclasses.asdict(recorded)
    diff = _differences(record, cfg.controller)
    if not diff:
        return cfg
    if user_sets_trot(args):
        log(f"note: {what}: recorded under another trot controller: {controller_note(record, cfg.controller)}")
        return cfg
    log(f"{what}: recorded under the trot controller {_assignments(diff)}, and {walked} (--no-recorded-trot walks "
        f"the config's own)")
    return with_trot(cfg, record)


def walk_under_recorded_trot(args, cfg: C.WalkConfig, learned: LearnedSet, log=print) -> C.WalkConfig:
    """The walk config of a comparison of `learned`: under the trot its paths share (`recorded_trot`, `trot_for`);
    where they do not share one, `cfg` as it is, with a note for each path recorded under another."""
    shared = recorded_trot(learned)
    if shared is None:
        note_controllers(learned, cfg, log)
        return cfg
    return trot_for(args, cfg, shared, "the learned paths", log)


def made_under(provenance: dict, cfg: C.WalkConfig) -> dict:
    """The provenance of a path rewritten while walking under `cfg`'s trot (`stance-force`, `pd-match`): that trot
    as the one the path is recorded under (`controller`), since the rewritten path is a gait of the trot it was
    made on and a later evaluation walks it there; the source path's own record kept as `source_controller` where
    the two differ (a `--set controller.*` at the rewrite)."""
    source = provenance.get("controller")
    out = {**provenance, "controller": dataclasses.asdict(cfg.controller)}
    if source is not None and _differences(source, cfg.controller):
        out["source_controller"] = source
    return out


def searched_trot(reference) -> dict | None:
    """The trot controller a searched shape (`tools/optimize_trajectory.py`'s `SampledTrajectory`) was searched
    under: the default `ControllerConfig` with the search's `--set controller.*` (its provenance's
    `walk_overrides`); None where the provenance does not say (a search run with --config, or no record)."""
    prov = getattr(reference, "provenance", None) or {}
    overrides = prov.get("walk_overrides")
    if overrides is None:  # written before the search recorded its overrides: its command line tells
        command = prov.get("command")
        if not isinstance(command, str) or "--set" in command or "--config" in command:
            return None
        overrides = []
    mine = [o for o in overrides if str(o).split("=", 1)[0].strip().startswith("controller.")]
    try:
        return dataclasses.asdict(C.override(C.WalkConfig(), mine).controller)
    except ValueError:  # a field this version lacks
        return None


def searched_controller(reference, walked: C.ControllerConfig, log=print) -> dict:
    """{"searched": the trot controller the searched shape `reference` was searched under} where that is not
    `walked`: the prototype's reference row walks each shape under its own trot (the best a user has of it), as
    `run_prototype(own_trot=...)` takes it; {} where it is the same, or not recorded."""
    from cyberdog.analysis.prototype_summary import REFERENCE

    own = searched_trot(reference) if reference is not None else None
    if own is None or C.from_dict(C.ControllerConfig, own) == walked:
        return {}
    diff = ", ".join(f"{k} {r}" for k, (r, w) in _differences(own, walked).items())
    log(f"the searched shape walks under the trot it was searched under ({diff})")
    return {REFERENCE: C.from_dict(C.ControllerConfig, own)}


def note_searched_trot(reference, cfg: C.WalkConfig, log=print) -> str:
    """Log, and return, a note where the searched shape `reference` was searched under another trot controller
    than the one `cfg` walks it under: its row then compares a shape found for another trot ("" otherwise)."""
    searched = searched_trot(reference) if reference is not None else None
    diff = _differences(searched, cfg.controller) if searched is not None else {}
    if not diff:
        return ""
    what = ", ".join(f"{k} {r} searched, {w} here" for k, (r, w) in diff.items())
    note = (f"note: the searched shape was searched under another trot controller ({what}): a shape searched "
            f"under this one (tools/optimize_trajectory.py --set "
            f"{' '.join(f'controller.{k}={w}' for k, (_, w) in diff.items())} ...) is the fairer reference")
    log(note)
    return note


def _differences(recorded: C.ControllerConfig | dict, walked: C.ControllerConfig) -> dict:
    rec = recorded if isinstance(recorded, dict) else dataclasses.asdict(recorded)
    now = dataclasses.asdict(walked)
    return {k: (v, now[k]) for k, v in rec.items() if k in now and now[k] != v}


def _assignments(diff: dict) -> str:
    return " ".join(f"controller.{k}={r}" for k, (r, _) in diff.items())
