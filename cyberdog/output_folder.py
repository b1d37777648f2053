"""Output folders of `evaluate.py`: the results of two runs never mix silently, and a run that failed can be
run again.

A folder that already holds files is refused unless the user asks to write into it (`force=True`); then the
files that previous runs recorded in the folder's `outputs.json` are removed first, so that `config.yaml` and
every result recorded there come from this run. Files no run recorded (a folder written before
`outputs.json` existed, or someone else's) are kept and named in a note. `append=True` is for a run that
adds to the results it reads from the same folder (`evaluate.py figures --from DIR`): nothing is refused or
removed.

Every run is entered in `outputs.json` as it starts (status "running", its start time) and, however it ends,
with exactly the files it wrote (new or rewritten) and its status: "finished", or "failed" / "interrupted"
(`abandon`). A file rewritten by a later run leaves the previous run's list. A run killed outright stays
"running"; the files in the folder written after its start are taken as its own. So the folder says what is
whose, `finish()` returns exactly this run's files for the summary, and a folder that holds only what runs
that did not finish left behind is emptied of it and reused without `--force`. Standard library only.
"""
from __future__ import annotations

import json
import os
import time
from pathlib import Path

MANIFEST = "outputs.json"
FORMAT = "cyberdog-evaluate-outputs"


class OutputFolderError(RuntimeError):
    """The output folder cannot be used as asked; the message says what to do."""


def _snapshot(out: Path) -> dict[str, tuple]:
    """Every file under `out` (but the manifest): relative path -> (mtime_ns, size, inode)."""
    if not out.is_dir():
        return {}
    files = {}
    for p in out.rglob("*"):
        if p.is_file() and not p.is_symlink():
            st = p.stat()
            files[p.relative_to(out).as_posix()] = (st.st_mtime_ns, st.st_size, st.st_ino)
    files.pop(MANIFEST, None)
    return files


def read_manifest(out: str | Path) -> dict:
    """The folder's outputs.json ({"runs": []} if there is none or it cannot be read)."""
    try:
        data = json.loads((Path(out) / MANIFEST).read_text())
        if isinstance(data, dict) and data.get("format") == FORMAT and isinstance(data.get("runs"), list):
            return data
    except (OSError, ValueError):
        pass
    return {"format": FORMAT, "runs": []}


def _examples(names, n: int = 3) -> str:
    names = sorted(names)
    return ", ".join(names[:n]) + (f" and {len(names) - n} more" if len(names) > n else "")


class OutputFolder:
    """One run's use of the output folder `out`: `OutputFolder(out, ...)` before writing, `finish()` after."""

    def __init__(self, out: str | Path, force: bool = False, append: bool = False, command: str = "",
                 argv=()):
        self.out, self.command, self.argv = Path(out), command, [str(a) for a in argv]
        self.notes: list[str] = []
        self.removed: list[Path] = []
        if self.out.exists() and not self.out.is_dir():
            raise OutputFolderError(f"--out {self.out} is a file, not a folder")
        existing = _snapshot(self.out)
        if existing and not append:
            unfinished = _unfinished_files(self.out, existing)
            if set(existing) <= unfinished:  # only what runs that did not finish left: theirs to replace
                self._remove(unfinished, "a previous run that did not finish")
            elif not force:
                raise OutputFolderError(
                    f"--out {self.out} already holds {len(existing)} file(s) ({_examples(existing)}): this run's "
                    f"results would mix with them; choose a new --out, or pass --force to replace the results "
                    f"that previous evaluate.py runs wrote there")
            else:
                self._remove_earlier(existing, unfinished)
        self.started = time.time()
        self.before = _snapshot(self.out)
        self._record("running", [])  # entered now: a failure or a kill still leaves this run named

    def _remove_earlier(self, existing: dict, unfinished: set[str]) -> None:
        recorded = {f for run in read_manifest(self.out)["runs"] for f in run.get("files", [])} | unfinished
        self._remove(recorded & set(existing), "previous evaluate.py runs", "--force: ")
        kept = set(existing) - recorded
        if kept:
            self.notes.append(f"--force: kept {len(kept)} file(s) in {self.out} that no evaluate.py run recorded "
                              f"({_examples(kept)}); {MANIFEST} lists the files this run writes")

    def _remove(self, names, whose: str, prefix: str = "") -> None:
        """Delete the files `names` (relative to the folder) and the manifest, then folders left empty."""
        for rel in sorted(names):
            path = self.out / rel
            path.unlink()
            self.removed.append(path)
        (self.out / MANIFEST).unlink(missing_ok=True)
        emptied = {p.parent for p in self.removed if p.parent != self.out}
        for d in sorted(emptied, key=lambda p: len(p.parts), reverse=True):  # e.g. learned/
            if d.is_dir() and not any(d.iterdir()):
                d.rmdir()
        if self.removed:
            self.notes.append(f"{prefix}removed {len(self.removed)} file(s) that {whose} wrote in {self.out}")

    def written(self) -> list[Path]:
        """The files this run has written so far (new, or rewritten since it started)."""
        now = _snapshot(self.out)
        return [self.out / rel for rel, stat in sorted(now.items()) if self.before.get(rel) != stat]

    def finish(self) -> list[Path]:
        """Record this run as finished in outputs.json; returns the files it wrote, outputs.json included."""
        files = self._record("finished", self.written())
        return files + [self.out / MANIFEST]

    def abandon(self, status: str = "failed") -> None:
        """Record this run as ended without finishing ("failed" or "interrupted"), with the files it wrote, so
        that the same command can run again into this folder."""
        self._record(status, self.written())

    def _record(self, status: str, files: list[Path]) -> list[Path]:
        """This run's entry in outputs.json with `status` and `files` (a file now this run's leaves previous
        runs' lists); written atomically."""
        rel = [p.relative_to(self.out).as_posix() for p in files]
        manifest = read_manifest(self.out)
        mine = set(rel)
        runs = []
        for run in manifest["runs"]:
            if run.get("started_ns") == self._started_ns():
                continue  # this run's own entry, written at its start
            run["files"] = [f for f in run.get("files", []) if f not in mine and (self.out / f).is_file()]
            if run["files"] or run.get("status", "finished") == "running":
                runs.append(run)
        entry = {"command": self.command, "argv": self.argv,
                 "started": time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(self.started)),
                 "started_ns": self._started_ns(), "status": status, "files": rel}
        if status != "running":
            entry["ended"] = time.strftime("%Y-%m-%d %H:%M:%S")
        manifest["runs"] = runs + [entry]
        self.out.mkdir(parents=True, exist_ok=True)
        tmp = self.out / f".{MANIFEST}.{os.getpid()}.tmp"
        tmp.write_text(json.dumps(manifest, indent=1) + "\n")
        os.replace(tmp, self.out / MANIFEST)
        return files

    def _started_ns(self) -> int:
        return int(self.started * 1e9)


def _unfinished_files(out: Path, existing: dict) -> set[str]:
    """The files of `existing` that runs which did not finish left: those they recorded (failed, interrupted),
    and, for a run still marked running (killed outright), every file written since it started that no
    finished run recorded."""
    runs = read_manifest(out)["runs"]
    finished = {f for r in runs if r.get("status", "finished") == "finished" for f in r.get("files", [])}
    mine = {f for r in runs if r.get("status") in ("failed", "interrupted") for f in r.get("files", [])}
    starts = [r["started_ns"] for r in runs if r.get("status") == "running" and "started_ns" in r]
    if starts:  # (file times come from a coarser clock than time.time(): a second's margin)
        since = min(starts) - 1_000_000_000
        mine |= {rel for rel, (mtime_ns, _, _) in existing.items() if mtime_ns >= since and rel not in finished}
    return mine & set(existing)
