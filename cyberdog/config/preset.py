"""A preset: one YAML file that is a whole recipe, stated as its change from what it builds on.

    base: table5.yaml          # optional: the preset this one changes (a path beside this file)
    summary: one line          # what the recipe makes (train.py --help lists it)
    env: {...}                 # ExperimentConfig sections: only what differs from the base (or the defaults)
    agent: {...}
    train: {...}
    phases:                    # optional, in order; default: one phase `train`, stage both
      - {name: stage1, stage: 1, preset: table5.yaml}     # this phase trains with another preset's settings
      - {name: stage2, stage: 2}                          # this preset's settings; starts from stage1's agent
      - name: band
        stage: 2
        set: {train: {stage2: {max_env_steps: 30000}}}    # changes to the phase before it (stage2)
      - {name: other, stage: 1, from: stage2/stage1_final.pt}  # band's settings; starts from another file
    extract: {replay_attempts: 16, candidates: 2}         # evaluate.py extract's settings for this recipe
                                                          # (replay_check: false keeps each policy's first path)

A phase's `stage` is the part of the two-stage training it runs: 1 (with the `train.stage1` settings), 2 (with
`train.stage2`) or both. Each phase's settings are those of the phase before it with the phase's `set:` laid over
them; the first phase's, the preset's own settings (the sections above) with its `set:`. A phase with `preset:`
trains with that preset's settings (its `set:` laid over them) for itself alone: the phase after it changes the
settings in force before it. A phase trains in `<seed folder>/<phase name>/` (an ordinary run folder) and starts from the previous phase's
last final agent (`<previous>/stage<N>_final.pt`) unless `from:` names another file of the same seed folder; the
first phase starts from nothing. A preset without `phases` or `extract` takes its base's. Sections merge key by
key over the base, and a phase's `set:` over the settings it changes (a list replaces the list). Every error is one
`ValueError` line naming the file.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cyberdog.config.io import (from_dict, is_preset, load_fields, merged, override, read_config_file, replace,
                                to_dict)
from cyberdog.config.learning import ExperimentConfig

SECTIONS = ("env", "agent", "train")
KEYS = ("base", "summary", "phases", "extract") + SECTIONS
PHASE_KEYS = ("name", "stage", "preset", "set", "from")
STAGES = ("1", "2", "both")
# evaluate.py extract's options a preset may set, and what each must be
EXTRACT_KEYS = {"replay_attempts": int, "candidates": int, "rollout_duration": float, "cycle": str,
                "replay_check": bool}
EXTRACT_CYCLES = ("mean", "cheapest")  # extract --cycle's choices (cyberdog.analysis.extract.CYCLE_CHOICES)
_NAME = re.compile(r"[a-z][a-z0-9_]*")


@dataclass(frozen=True)
class Phase:
    """One step of a recipe: a training run of `stage` ("1", "2" or "both") with `config`, in `<seed>/<name>/`,
    started from `start` (a file relative to the seed folder; None: from nothing)."""

    name: str
    stage: str
    config: ExperimentConfig
    start: str | None = None

    @property
    def last_stage(self) -> int:
        return 2 if self.stage == "both" else int(self.stage)

    @property
    def final_agent(self) -> str:
        """The file this phase leaves for the next, relative to the seed folder."""
        return f"{self.name}/stage{self.last_stage}_final.pt"


@dataclass(frozen=True)
class Preset:
    """A resolved preset file: its settings, its phases (each with its own settings) and its extraction."""

    path: Path
    summary: str
    config: ExperimentConfig
    phases: tuple[Phase, ...]
    extract: dict = field(default_factory=dict)
    bases: tuple[Path, ...] = ()  # the chain of base files, nearest first

    @property
    def name(self) -> str:
        return self.path.stem

    @property
    def phased(self) -> bool:
        """More than the plain two-stage run of one config (train.py's run of a config without phases)."""
        return len(self.phases) > 1 or self.phases[0].start is not None or self.phases[0].name != "train"


def read_raw(path: str | Path, _chain: tuple[Path, ...] = ()) -> tuple[dict, tuple[Path, ...]]:
    """The preset's sections, phases and extraction with its base chain merged in (not yet typed), and the
    chain of base files. A base loop, a missing base or an unknown key is one ValueError line."""
    path = Path(path).resolve()
    if path in _chain:
        loop = " -> ".join(p.name for p in (*_chain, path))
        raise ValueError(f"{_chain[0]}: base loop {loop}")
    if path.is_dir():
        raise ValueError(f"config {path} is a folder, expected a YAML file")
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as e:
        raise ValueError(f"config {path} is not valid YAML: {' '.join(str(e).split())}") from None
    except OSError as e:
        where = f" (the base of {_chain[-1]})" if _chain else ""
        raise ValueError(f"config {path}{where} cannot be read: {e.strerror or e}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a preset is a mapping of {', '.join(KEYS)}, got {type(data).__name__}")
    unknown = sorted(set(data) - set(KEYS), key=str)
    if unknown:
        raise ValueError(f"{path}: unknown key(s) {unknown}; a preset has {', '.join(KEYS)}")
    chain = (*_chain, path)
    if data.get("base") is None:
        raw: dict = {}
        bases: tuple[Path, ...] = ()
    else:
        if not isinstance(data["base"], str):
            raise ValueError(f"{path}: base must be a file name beside it, e.g. base: table5.yaml, got {data['base']!r}")
        raw, bases = read_raw(path.parent / data["base"], chain)
        bases = (path.parent / data["base"], *bases)
    for key in SECTIONS:
        if data.get(key) is not None:
            if not isinstance(data[key], dict):
                raise ValueError(f"{path}: {key} must be a mapping of settings, got {data[key]!r}")
            raw[key] = merged(raw.get(key, {}), data[key])
    for key in ("phases", "extract", "summary"):
        if key in data:
            raw[key] = data[key]
            raw[f"{key}_from"] = path
    return raw, tuple(Path(b).resolve() for b in bases)


def load_preset(path: str | Path, overrides: list[str] = ()) -> Preset:
    """Read and resolve a preset file (module docstring); `overrides` (`section.field=value`, as train.py's
    --set) apply to the settings of every phase."""
    path = Path(path)
    raw, bases = read_raw(path)
    body = {k: raw[k] for k in SECTIONS if k in raw}
    try:
        config = override(from_dict(ExperimentConfig, body), list(overrides))
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None
    summary = raw.get("summary") or ""
    if not isinstance(summary, str):
        raise ValueError(f"{path}: summary must be one line of text, got {summary!r}")
    phases = _phases(raw.get("phases"), raw.get("phases_from", path), body, list(overrides))
    return Preset(path=path, summary=" ".join(summary.split()), config=config, phases=phases,
                  extract=_extract(raw.get("extract"), raw.get("extract_from", path)), bases=bases)


def load(cls: type, path: str | Path) -> Any:
    """Read a YAML config file of `cls` (`cyberdog.config.load`): a file of its fields, or for ExperimentConfig
    also a preset file (its settings, `load_preset(path).config`). A missing file raises `FileNotFoundError`, a
    folder, bad YAML or values `ValueError` (a preset given for another class: one line saying so)."""
    if cls is ExperimentConfig and is_preset(read_config_file(path)):
        return load_preset(path).config
    return load_fields(cls, path)


def _phases(spec: Any, where: Path, body: dict, overrides: list[str]) -> tuple[Phase, ...]:
    """The typed phases of a preset's `phases:` list (None: one phase `train`, both stages), each phase's settings
    the previous phase's with its `set:` laid over them (the first phase's: `body`'s)."""
    if spec is None:
        spec = [{"name": "train", "stage": "both"}]
    if not isinstance(spec, list) or not spec:
        raise ValueError(f"{where}: phases must be a non-empty list of {{name, stage, ...}}, got {spec!r}")
    phases: list[Phase] = []
    in_force = body  # the settings the next phase's `set:` changes
    for i, item in enumerate(spec):
        label = _phase_label(item, i, where, phases)
        stage = str(item.get("stage", "both"))
        settings = in_force
        if item.get("preset") is not None:  # another preset's settings, for this phase alone
            settings = {k: v for k, v in read_raw(where.parent / str(item["preset"]))[0].items() if k in SECTIONS}
        if item.get("set") is not None:
            if not isinstance(item["set"], dict) or set(item["set"]) - set(SECTIONS):
                raise ValueError(f"{label}: set must be a mapping of {', '.join(SECTIONS)} sections, got {item['set']!r}")
            settings = merged(settings, item["set"])
        if item.get("preset") is None:
            in_force = settings
        try:
            config = override(from_dict(ExperimentConfig, settings), overrides)
        except ValueError as e:
            raise ValueError(f"{label}: {e}") from None
        phases.append(Phase(name=item["name"], stage=stage, config=config, start=_phase_start(item, label, phases)))
    return tuple(phases)


def _phase_label(item: Any, i: int, where: Path, phases: list[Phase]) -> str:
    """'<file>: phase <name>' for the errors of phase `i` (`item`), after checking its keys, name and stage."""
    if not isinstance(item, dict):
        raise ValueError(f"{where}: phase {i + 1} must be a mapping with {', '.join(PHASE_KEYS)}, got {item!r}")
    name = item.get("name")
    label = f"{where}: phase {name!r}" if isinstance(name, str) else f"{where}: phase {i + 1}"
    unknown = sorted(set(item) - set(PHASE_KEYS), key=str)
    if unknown:
        raise ValueError(f"{label}: unknown key(s) {unknown}; a phase has {', '.join(PHASE_KEYS)}")
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ValueError(f"{label}: name must be lower-case letters, digits and _ (a folder name), got {name!r}")
    if name in (p.name for p in phases):
        raise ValueError(f"{label}: the name is used by a phase before it")
    if str(item.get("stage", "both")) not in STAGES:
        raise ValueError(f"{label}: stage must be 1, 2 or both, got {item.get('stage')!r}")
    return label


def _phase_start(item: dict, label: str, phases: list[Phase]) -> str | None:
    """The file (relative to the seed folder) phase `item` starts from: `from:`, else the previous phase's final
    agent; None for a first phase (which must then train stage 1)."""
    start = item.get("from", phases[-1].final_agent if phases else None)
    if start is not None:
        first = str(start).split("/")[0]
        if first not in (p.name for p in phases):
            raise ValueError(f"{label}: from {start!r} must be a file of a phase before it "
                             f"({', '.join(p.name for p in phases) or 'none before this one'})")
    if str(item.get("stage", "both")) == "2" and start is None:
        raise ValueError(f"{label}: stage 2 alone starts from the agent of a phase before it; the first phase "
                         f"trains stage 1 or both")
    return start


def _extract(spec: Any, where: Path) -> dict:
    if spec is None:
        return {}
    if not isinstance(spec, dict):
        raise ValueError(f"{where}: extract must be a mapping of evaluate.py extract settings, got {spec!r}")
    out = {}
    for key, value in spec.items():
        kind = EXTRACT_KEYS.get(key)
        if kind is None:
            raise ValueError(f"{where}: extract.{key} is not an extraction setting ({', '.join(EXTRACT_KEYS)})")
        if kind is bool:
            if not isinstance(value, bool):
                raise ValueError(f"{where}: extract.{key} must be true or false, got {value!r}")
            out[key] = value
            continue
        ok = not isinstance(value, bool) and (isinstance(value, kind) or (kind is float and isinstance(value, int)))
        if not ok or (kind is not str and value <= 0) or (key == "cycle" and value not in EXTRACT_CYCLES):
            what = f"one of {EXTRACT_CYCLES}" if key == "cycle" else f"a positive {'integer' if kind is int else 'number'}"
            raise ValueError(f"{where}: extract.{key} must be {what}, got {value!r}")
        out[key] = kind(value)
    return out


def changed_settings(config, reference=None) -> dict[str, tuple]:
    """{dotted.setting: (value, reference value)} of every setting of `config` (an ExperimentConfig, or another
    config dataclass such as a WalkConfig) that differs from `reference` (default: ExperimentConfig())."""
    def flat(d: dict, prefix: str = "") -> dict:
        out = {}
        for k, v in d.items():
            out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {f"{prefix}{k}": v})
        return out

    mine, ref = flat(to_dict(config)), flat(to_dict(reference or ExperimentConfig()))
    return {k: (v, ref.get(k)) for k, v in mine.items() if v != ref.get(k)}


def describe(preset: Preset) -> str:
    """The preset's resolved settings as their difference from the defaults, phase by phase (train.py --show)."""
    lines = [f"{preset.path}: {preset.summary or '(no summary)'}"]
    if preset.bases:
        lines.append("builds on: " + " -> ".join(str(b.name) for b in preset.bases))
    previous = None
    for phase in preset.phases:
        start = f", starts from <seed>/{phase.start}" if phase.start else ""
        lines.append(f"\nphase {phase.name} (stage {phase.stage}{start}):")
        if previous is None:
            diff = changed_settings(phase.config)
            lines += [f"  {k} = {v!r}   (default {d!r})" for k, (v, d) in diff.items()] or ["  (the defaults)"]
        else:
            diff = changed_settings(phase.config, previous)
            lines += [f"  {k} = {v!r}   (previous phase {d!r})" for k, (v, d) in diff.items()] or [
                "  (the previous phase's settings)"]
        previous = phase.config
    if preset.extract:
        lines.append("\nextract: " + ", ".join(f"{k}={v}" for k, v in preset.extract.items()))
    return "\n".join(lines)


def preset_summaries(folder: str | Path) -> list[tuple[str, str]]:
    """(file name, summary) of every preset at the top of `folder` (train.py --help); unreadable ones say so."""
    out = []
    for path in sorted(Path(folder).glob("*.yaml")):
        try:
            data = yaml.safe_load(path.read_text()) or {}
            summary = " ".join(str(data.get("summary", "")).split()) if isinstance(data, dict) else ""
        except (OSError, yaml.YAMLError):
            summary = "(unreadable)"
        out.append((path.name, summary))
    return out


# ---- a seed's lineage: the phases a run folder trains, written when it starts (train.py, a sweep's seed) -------
PHASES_FILE = "phases.yaml"


def write_phases(folder: str | Path, preset: Preset, seed: int) -> Path:
    """`folder`/phases.yaml: every phase's resolved settings for `seed`, so that `train.py --resume folder`
    continues the lineage as it was resolved when it began (the preset file may change since)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data = {"preset": str(preset.path), "seed": int(seed), "extract": dict(preset.extract),
            "phases": [{"name": p.name, "stage": p.stage, "from": p.start,
                        "config": to_dict(replace(p.config, train=replace(p.config.train, seed=int(seed))))}
                       for p in preset.phases]}
    path = folder / PHASES_FILE
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(yaml.safe_dump(data, sort_keys=False))
    tmp.replace(path)
    return path


def read_phases(folder: str | Path) -> tuple[tuple[Phase, ...], dict]:
    """The phases (and the extraction settings) of a lineage folder's phases.yaml, or of such a file given
    itself (a shipped policy folder keeps it as recipe_phases.yaml: it is not a lineage to train or resume)."""
    path = Path(folder) if Path(folder).is_file() else Path(folder) / PHASES_FILE
    try:
        data = yaml.safe_load(path.read_text())
        phases = tuple(Phase(name=p["name"], stage=str(p["stage"]), start=p.get("from"),
                             config=from_dict(ExperimentConfig, p["config"])) for p in data["phases"])
        return phases, dict(data.get("extract") or {})
    except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError) as e:
        raise ValueError(f"{path} cannot be read as a lineage: {e}") from None


def is_lineage(folder: str | Path) -> bool:
    return (Path(folder) / PHASES_FILE).is_file()


def final_run(folder: str | Path) -> Path:
    """The run folder whose actors a lineage folder ends with (its last phase's), or `folder` itself."""
    folder = Path(folder)
    if not is_lineage(folder):
        return folder
    return folder / read_phases(folder)[0][-1].name


def phase_names(folder: str | Path) -> tuple[str, ...]:
    """A lineage folder's phase names in order; () for a folder that is not a lineage."""
    return tuple(p.name for p in read_phases(folder)[0]) if is_lineage(folder) else ()


def current_run(folder: str | Path, names: tuple[str, ...] | None = None) -> Path:
    """The run folder a lineage folder is training now (its last phase folder with a metrics.csv; the first
    phase's before any), or `folder` itself. `names`: the lineage's `phase_names`, where the caller keeps them
    (parsing phases.yaml, every phase's whole settings, takes tens of ms)."""
    folder = Path(folder)
    names = phase_names(folder) if names is None else names
    if not names:
        return folder
    started = [n for n in names if (folder / n / "metrics.csv").is_file()]
    return folder / (started[-1] if started else names[0])
