"""One `evaluate.py` run's output folder: refused if it holds results (unless --force), config.yaml written for a
run that walks (the whole robot it walks: the walk config and the hardware model, `cyberdog.config.walked`), and
at the end the list of exactly the files the run wrote."""
from __future__ import annotations

import time
from pathlib import Path

from cyberdog import config as C
from cyberdog.evaluation.options import UsageError


class Run:
    """One evaluate.py run's output folder: refused if it holds results (unless --force), and at the end the
    list of exactly the files this run wrote (recorded in the folder's outputs.json)."""

    def __init__(self, args, out: Path, append: bool = False):
        from cyberdog.output_folder import OutputFolder, OutputFolderError

        self.out, self.t0 = out, time.perf_counter()
        self.hardware = args.walked_hardware  # the hardware-like walks' model (None: the ideal robot only)
        try:
            self.folder = OutputFolder(out, force=args.force, append=append, command=args.command,
                                       argv=getattr(args, "argv", ()))
        except OutputFolderError as err:
            raise UsageError(str(err)) from None
        for note in self.folder.notes:
            print(note)
        args.run = self  # so that `run` can record this run's files if the command fails

    def save_config(self, cfg: C.WalkConfig, name: str = "config.yaml") -> None:
        """Write the robot the run walks as `name`: `cfg` and the run's hardware model (`cyberdog.config.walked`),
        which --config reads back."""
        C.save_walked(C.WalkedRobot(cfg, self.hardware), self.out / name)

    def abandon(self, status: str) -> None:
        """Record the files written so far, the run as `status` ("failed", "interrupted")."""
        self.folder.abandon(status)

    def finish(self, headline: str | None = None) -> int:
        """Record the run; print the files it wrote (with `headline`, a file of them: only where the headline
        and the figures are, and how many files in all)."""
        files = self.folder.finish()
        print(f"\nwrote {len(files)} files in {self.out}/ ({time.perf_counter() - self.t0:.1f} s)"
              + ("; every file is listed in outputs.json" if headline else ":"))
        if headline:
            print(f"  the headline table:  {self.out / headline}")
            figures = sorted(p.name for p in files if p.suffix == ".png")
            if figures:
                print(f"  the figures:         {self.out}/{{{','.join(figures)}}}")
        else:
            for p in files:
                print(f"  {p}")
        print(f"output folder: {self.out}/")  # the last line: where to look
        return 0


def new_out() -> Path:
    """runs/evaluate-<time>, with a suffix if a run in the same second took that name."""
    base = Path("runs") / time.strftime("evaluate-%Y%m%d-%H%M%S")
    out, k = base, 1
    while out.exists():
        k += 1
        out = base.with_name(f"{base.name}-{k}")
    return out


def open_run(args, cfg: C.WalkConfig) -> Run:
    """The output folder of a sub-command that walks: --out (default runs/evaluate-<time>) with config.yaml, the
    walk config `cfg` and the hardware model of the run's hardware-like walks (`Run.save_config`)."""
    out = args.out or new_out()
    try:
        run = Run(args, out)
        run.save_config(cfg)
    except OSError as err:  # an unwritable place, or a path through a file
        raise UsageError(f"cannot write the output folder --out {out}: {err.strerror or err}; choose a folder "
                         f"you can write") from None
    return run
