"""The README is the project's contract with a new user: its two set-up commands (CI runs the second), and every
command it suggests next works as written after them. Cheap commands are run (their output folders moved into
a temporary folder); commands that train or walk for minutes are parsed by their own command line, with the
reason they are not run listed in EXPENSIVE; the TensorBoard server is checked to be installed."""
from __future__ import annotations

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
VENV_PYTHON = ".venv/bin/python"
OUTPUT_OPTIONS = ("--run-dir", "--out")  # what a run writes to: moved into tmp_path

# the start of each README command that is not run here, and why (each is parsed instead)
EXPENSIVE = {
    "train.py --config configs/table5.yaml --seeds 5-9": "the Table 5 recipe on five seeds: about an hour",
    "evaluate.py extract --sweep runs/table5": "needs the sweep above; rolls out 5 policies at 3 speeds",
    "evaluate.py compare --learned runs/table5_paths/learned": "needs the extraction above; walks for minutes",
    "train.py --config configs/battery.yaml --seeds 5-9": "the battery recipe's three phases on five seeds: hours",
    "evaluate.py extract --sweep runs/battery_searched": "needs the sweep above; up to 16 rollouts per seed and speed",
    "evaluate.py prototype --learned runs/bs_paths/learned": "needs the extraction above; 112 walks of 20 m",
    "train.py --config configs/torque.yaml --seeds 0-4": "the paper's torque agent: 850,000 env steps a seed, hours",
    "train.py --config configs/battery_searched.yaml --seeds 20-24": "the battery from the searched shape: hours",
    "train.py --config configs/battery_searched.yaml --seeds 40-44,140-144": "the same, ten lineages: hours",
    "evaluate.py extract --sweep runs/bs_pick": "needs the sweep above; ten lineages' rollouts",
    "evaluate.py pick --learned runs/bs_pick_paths/learned": "needs the extraction above",
}
SERVER = {".venv/bin/tensorboard --logdir runs": "a server that runs until stopped: checked to be installed"}
RUN = ("train.py --config configs/tiny.yaml", "-m plots --from results/figures_input", "train.py --help",
       "evaluate.py --help")


def bash_blocks() -> list[str]:
    return re.findall(r"```bash\n(.*?)```", README, flags=re.S)


def readme_commands():
    """The two set-up commands (the first two bash blocks)."""
    return [line for b in bash_blocks()[:2] for line in b.splitlines() if line and not line.startswith("#")]


def next_commands() -> list[str]:
    """Every command of the later bash blocks, without its trailing comment."""
    lines = [ln.split("  #")[0].strip() for b in bash_blocks()[2:] for ln in b.splitlines()]
    return [ln for ln in lines if ln and not ln.startswith("#")]


def python_args(command: str) -> list[str]:
    """The arguments after the environment's Python, output folders as written."""
    assert command.startswith(VENV_PYTHON + " "), f"use the environment's Python: {command}"
    return shlex.split(command)[1:]


def redirected(args: list[str], tmp_path: Path) -> list[str]:
    return [str(tmp_path / a) if i and args[i - 1] in OUTPUT_OPTIONS else a for i, a in enumerate(args)]


def kind(command: str) -> str:
    rest = command.removeprefix(VENV_PYTHON + " ")
    kinds = ([k for k in EXPENSIVE if rest.startswith(k)] and ["parse"]) + \
            ([k for k in SERVER if command.startswith(k)] and ["server"]) + \
            ([k for k in RUN if rest.startswith(k)] and ["run"])
    assert len(kinds) == 1, f"README command not classified (or twice) in tests/test_readme.py: {command}"
    return kinds[0]


# ---- the two set-up commands ------------------------------------------------------------------------------------
def test_readme_opens_with_two_commands_pinning_torch_first():
    commands = readme_commands()
    assert len(commands) == 2
    for c in commands:
        assert c.index("torch==2.13.0") < c.index(" -e "), "torch must be pinned before the package installs"
    assert "evaluate.py" in commands[0] and "pytest" in commands[1]


def test_ci_runs_exactly_the_readme_test_command():
    ci_lines = [ln for ln in (ROOT / ".ci" / "run").read_text().splitlines()
                if ln and not ln.startswith("#") and not ln.startswith(("set ", "cd "))]
    assert ci_lines == [readme_commands()[1]]


# ---- the README itself ------------------------------------------------------------------------------------------
def test_readme_is_short_and_its_links_and_images_exist():
    assert len(README.splitlines()) <= 190
    targets = re.findall(r"\]\(([^)#]+)\)", README)
    local = [t for t in targets if not t.startswith("http")]
    assert any(t.endswith(".png") for t in local) and any(t.startswith("docs/") for t in local)
    assert [t for t in local if not (ROOT / t).exists()] == []


def test_every_next_command_is_classified_and_uses_the_environment():
    commands = next_commands()
    assert len(commands) >= len(RUN) + len(EXPENSIVE)
    kinds = [kind(c) for c in commands]
    assert kinds.count("run") == len(RUN) and kinds.count("parse") == len(EXPENSIVE)


# ---- running them ----------------------------------------------------------------------------------------------
def commands_of(k: str) -> list[str]:
    return [c for c in next_commands() if kind(c) == k]


@pytest.mark.parametrize("command", [c for c in commands_of("run") if "configs/tiny.yaml" not in c])
def test_cheap_next_commands_run_as_written(command, tmp_path):
    args = redirected(python_args(command), tmp_path)
    proc = subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    if "--help" in args:
        assert "usage:" in proc.stdout
    else:  # the README's figures, into tmp_path instead of plots/png
        out = Path(args[args.index("--out") + 1])
        assert sorted(p.name for p in out.glob("*.png")) == sorted(p.name for p in (ROOT / "plots/png").glob("*.png"))


@pytest.mark.slow  # about 30 s: most of it importing torch and TorchRL
def test_the_tiny_training_run_trains_both_stages(tmp_path):
    from cyberdog.metrics_csv import read_stages

    (command,) = [c for c in commands_of("run") if "configs/tiny.yaml" in c]
    args = redirected(python_args(command), tmp_path)
    proc = subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    run_dir = Path(args[args.index("--run-dir") + 1])
    assert sorted(read_stages(run_dir / "metrics.csv")) == [1, 2]
    assert (run_dir / "stage2_final_actor.pt").is_file()


@pytest.mark.parametrize("command", commands_of("parse"))
def test_expensive_next_commands_parse(command):
    """Not run (see EXPENSIVE for why): their options must be ones the command line takes, their configs load."""
    from cyberdog import config as C

    args = python_args(command)
    if args[0] == "train.py":
        from cyberdog import train_cli as train  # train.py's command line

        parsed = train.parse_args(args[1:])
        C.load_preset(ROOT / parsed.config, parsed.overrides)
    else:
        from cyberdog.evaluation.cli import parse_args

        assert parse_args(args[1:]).command == args[1]


@pytest.mark.parametrize("command", commands_of("server"))
def test_servers_are_installed(command):
    assert (Path(sys.executable).parent / Path(shlex.split(command)[0]).name).is_file()


def _readme_example() -> str:
    return re.search(r"```python\n(.*?)```", README, flags=re.S)[1]


def test_the_readme_python_example_runs_twice_quietly():
    """The README's ten lines, as written, run twice in a row from the repository root: no error, no traceback,
    no 'Exception ignored' at exit (each run trains into its own temporary folder)."""
    code = _readme_example()
    assert len(code.strip().splitlines()) <= 13
    for _ in range(2):
        proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr, proc.stderr[-2000:]
        speed, energy, fell = proc.stdout.split()[-3:]
        assert float(speed) > 0 and float(energy) > 0 and fell in ("True", "False")


def test_the_readme_python_example_says_where_to_run_it_from_another_folder(tmp_path):
    proc = subprocess.run([sys.executable, "-c", _readme_example()], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    last = proc.stderr.strip().splitlines()[-1]
    # the checkout named is the installed package's (this one, where the tests run from an editable install)
    assert proc.returncode != 0 and "it is in the checkout: run from " in last and "configs/tiny.yaml" in last, last


def test_the_environment_page_example_runs():
    code = re.search(r"```python\n(.*?)```", (ROOT / "docs" / "environment.md").read_text(), flags=re.S)[1]
    exec(compile(code, "docs/environment.md", "exec"), {})


@pytest.mark.parametrize("page", ["README.md", "docs/results.md"])
def test_the_result_tables_are_the_shipped_results_as_made(page):
    """The tables of the README and docs/results.md are `tools/make_readme_tables.py`'s output from
    results/figures_input/, to the printed digit; a changed result, or a hand edit, shows here. docs/results.md
    holds every table made (Table 5, the prototype run, the stiffness table where its walks are shipped), the
    README the ones it marks."""
    from cyberdog.analysis import searched_start_table
    from cyberdog.analysis.readme_tables import DOCUMENTS, FRESH_SEEDS, HEADLINES, NAMES, make_tables, readme_blocks
    blocks = readme_blocks((ROOT / page).read_text())
    tables = make_tables(ROOT / "results" / "figures_input")
    assert set(blocks) <= set(tables) <= set(NAMES)
    full = set(tables) - set(HEADLINES)
    if DOCUMENTS[page]:
        assert set(blocks) == full, f"{page} lacks the markers of {sorted(full - set(blocks))}"
    else:  # the README: the headline of every result shipped
        shipped = {name: spec for name, spec in HEADLINES.items() if spec[0] in tables}
        assert set(blocks) == set(shipped), f"{page} shows {sorted(blocks)}, not the headlines"
        for name, (source, rows) in shipped.items():
            recipe = {r.headline: r for r in searched_start_table.RECIPES}.get(name)
            if recipe is not None:  # its rows are named by the seeds shipped
                rows = searched_start_table.headline_of(ROOT / "results" / "figures_input", recipe)[0]
            # a fresh-seed row where it is shipped, named by the seeds it holds ("seeds 6–8" for "seeds 5–9")
            named = [re.escape(r).replace(re.escape(FRESH_SEEDS), r"seeds \d+–\d+") for r in rows]
            present = [r for r in named if re.search(rf"\| {r} \|", tables[source])]
            beside = sum("narrower stance" in r for r in rows)  # the rows against the stance-width search: beside
            assert blocks[name].count("\n") == len(present) + 1 <= 7 + beside and blocks[name] in tables[name]
    for name in blocks:
        assert blocks[name] == tables[name], \
            f"{page}'s {name} table differs: python tools/make_readme_tables.py --write"


def test_the_tables_are_made_from_saved_walks_without_loading_a_simulator_or_torch():
    """`tools/make_readme_tables.py` reads results/figures_input/ alone: in a fresh interpreter that makes every
    table, no physics engine, torch or walking code is imported."""
    forbidden = ("torch", "pybullet", "mujoco", "cyberdog.sim", "cyberdog.loop", "cyberdog.rl", "cyberdog.envs",
                 "cyberdog.analysis.walk", "cyberdog.analysis.compare")
    code = ("import json, sys\nfrom tools.make_readme_tables import main\nmain([])\n"
            "print(json.dumps(sorted(sys.modules)))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "| 1.0 m/s | 1.2 m/s | 1.4 m/s |" in proc.stdout  # the tables were made
    modules = json.loads(proc.stdout.strip().splitlines()[-1])
    assert [m for m in modules if any(m == f or m.startswith(f + ".") for f in forbidden)] == []


def test_writing_the_tables_fills_both_pages_and_refuses_a_results_page_without_markers(tmp_path):
    """`--write` rewrites every marked table of both pages (a README may mark fewer), and refuses, before
    writing anything, a docs/results.md that lacks a table's markers."""
    from cyberdog.analysis.readme_tables import HEADLINES, make_tables, write_documents
    tables = {n: t for n, t in make_tables(ROOT / "results" / "figures_input").items() if n not in HEADLINES}
    stale = {name: f"<!-- table:{name} -->\nstale\n<!-- /table:{name} -->" for name in tables}
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("intro\n" + stale["table5"] + "\nend\n")
    (tmp_path / "docs" / "results.md").write_text("\n\n".join(stale.values()) + "\n")
    assert write_documents(tmp_path, tables) == {"README.md": True, "docs/results.md": True}
    assert (tmp_path / "README.md").read_text() == f"intro\n<!-- table:table5 -->\n{tables['table5']}\n" \
                                                  "<!-- /table:table5 -->\nend\n"
    assert all(tables[n] in (tmp_path / "docs" / "results.md").read_text() for n in tables)
    assert write_documents(tmp_path, tables) == {"README.md": False, "docs/results.md": False}
    (tmp_path / "README.md").write_text(stale["table5"])
    (tmp_path / "docs" / "results.md").write_text(stale["table5"])
    with pytest.raises(ValueError, match="table:prototype.*docs/results.md"):
        write_documents(tmp_path, tables)
    assert (tmp_path / "README.md").read_text() == stale["table5"]  # nothing written


def test_the_readme_tables_follow_the_rows_they_are_made_from(tmp_path):
    """Each cell is its rows' mean ± CI: moving one seed's learned walk moves the table's cells for that speed
    only, and a README without a table's markers is refused by name."""
    import json
    from cyberdog.analysis.readme_tables import make_tables, replace_blocks
    source = ROOT / "results" / "figures_input"
    for name in ("comparison.json", "prototype.json"):
        (tmp_path / name).write_text((source / name).read_text())
    before = make_tables(tmp_path)
    walks = json.loads((tmp_path / "comparison.json").read_text())
    moved = next(w for w in walks if w["trajectory"] == "learned" and w["set"] == "same_lift"
                 and w["speed_command_mps"] == 1.2 and w["valid"])
    moved["energy_kJ"] += 0.5
    (tmp_path / "comparison.json").write_text(json.dumps(walks))
    after = make_tables(tmp_path)
    row = next(line for line in after["table5"].splitlines() if line.startswith("| E, learned (kJ)"))
    old = next(line for line in before["table5"].splitlines() if line.startswith("| E, learned (kJ)"))
    cells, old_cells = row.split(" | ")[1:], old.split(" | ")[1:]
    assert cells[0] == old_cells[0] and cells[1] != old_cells[1] and cells[2] == old_cells[2]
    assert after["prototype"] == before["prototype"]
    with pytest.raises(ValueError, match="table:prototype"):
        replace_blocks("no markers here", {"prototype": after["prototype"]})


def _shipped_inputs_with_seeds_5_9(tmp_path: Path, name: str) -> list[dict]:
    """Copies this engine's shipped table inputs into tmp_path and returns the walks of `name` among them with
    seeds 0-4 renamed 5-9: walks a table can take for a fresh set whose rows must equal the shipped ones."""
    import shutil

    from cyberdog.analysis.engine_table import TWIN_SUFFIX
    source = ROOT / "results" / "figures_input"
    for f in source.glob("*.json"):
        if not f.name.endswith(TWIN_SUFFIX):  # the other engine's twins walked the shipped paths, not these
            shutil.copy(f, tmp_path / f.name)
    relabel = {f"seed{k}": f"seed{k + 5}" for k in range(5)}
    return [dict(w, seed=relabel.get(str(w.get("seed")), w.get("seed")))
            for w in json.loads((source / name).read_text())]


def test_fresh_seeds_rows_are_those_seeds_walks_as_table5_summarises_them(tmp_path):
    """With comparison_fresh.json (the recipe's paths of seeds it was never tuned on) Table 5 gains their E and
    D_t rows, named by their seeds; the same walks relabelled give the shipped rows' numbers."""
    from cyberdog.analysis.readme_tables import make_tables
    walks = _shipped_inputs_with_seeds_5_9(tmp_path, "comparison.json")
    (tmp_path / "comparison_fresh.json").write_text(json.dumps(walks))
    table = make_tables(tmp_path)["table5"].splitlines()
    row = {line.split("|")[1].strip(): line.split("|")[2:5] for line in table[2:]}
    fresh = row["**D_t on E, seeds 5–9 (never tuned on)**"]
    assert [c.split(" (")[0].strip() for c in fresh] == [c.strip() for c in row["**D_t on E, Eq. 12**"]]
    assert row["E, learned, seeds 5–9 (kJ)"] == row["E, learned (kJ)"]


def test_fresh_seeds_prototype_rows_are_those_seeds_walks_as_the_prototype_summary_gives_them(tmp_path):
    """With prototype_fresh.json (the battery recipe's paths of seeds it was never tuned on, walked as the
    prototype run) the prototype table gains their battery, saving and against-the-search rows, named by their
    seeds (the last only where the run walked the searched shape); the same walks
    relabelled give the shipped rows' numbers, and a fresh walk that fell is counted in its cell."""
    from cyberdog.analysis.readme_tables import FRESH_PROTOTYPE_ROW, FRESH_VS_SEARCHED_ROW, make_tables
    fresh = _shipped_inputs_with_seeds_5_9(tmp_path, "prototype.json")
    (tmp_path / "prototype_fresh.json").write_text(json.dumps(fresh))
    tables = make_tables(tmp_path)
    row = {line.split("|")[1].strip(): line.split("|")[2:5] for line in tables["prototype"].splitlines()[2:]}
    assert row[FRESH_PROTOTYPE_ROW] == row["**battery saving against the cheaper common trajectory**"]
    assert row["battery % per 100 m: learned, seeds 5–9"] == row["battery % per 100 m: learned"]
    tuned_vs_searched = row["learned against the shape searched for the battery (the best alternative)"]
    assert row[FRESH_VS_SEARCHED_ROW] == tuned_vs_searched
    assert FRESH_PROTOTYPE_ROW in tables["prototype_headline"] and FRESH_VS_SEARCHED_ROW in tables["prototype_headline"]
    no_search = [w for w in fresh if w["trajectory"] != "searched"]  # a run without the reference: no such row
    (tmp_path / "prototype_fresh.json").write_text(json.dumps(no_search))
    assert FRESH_VS_SEARCHED_ROW not in make_tables(tmp_path)["prototype"]
    fell = next(w for w in fresh if w["trajectory"] == "learned" and w["speed_mps"] == 1.4)
    fell["fell"] = True
    (tmp_path / "prototype_fresh.json").write_text(json.dumps(fresh))
    row = {line.split("|")[1].strip(): line.split("|")[2:5]
           for line in make_tables(tmp_path)["prototype"].splitlines()[2:]}
    assert "1 fell" in row[FRESH_PROTOTYPE_ROW][2] and "fell" not in row[FRESH_PROTOTYPE_ROW][0]
    # a seed whose extraction found no path at 1.4 m/s: that cell says over how many seeds it is
    fresh = [w for w in fresh if not (w["seed"] == "seed5" and w["speed_mps"] == 1.4)]
    (tmp_path / "prototype_fresh.json").write_text(json.dumps(fresh))
    row = {line.split("|")[1].strip(): line.split("|")[2:5]
           for line in make_tables(tmp_path)["prototype"].splitlines()[2:]}
    assert "(4 of 5 seeds)" in row[FRESH_PROTOTYPE_ROW][2] and "seeds)" not in row[FRESH_PROTOTYPE_ROW][0]


def test_every_readme_table_names_the_command_that_prints_it_as_shown(capsys, monkeypatch):
    """Each README table's caption (the text since the table before it) names `--table NAME`, and
    `tools/make_readme_tables.py --table NAME` prints exactly the table the README shows."""
    monkeypatch.syspath_prepend(str(ROOT / "tools"))
    import make_readme_tables
    from cyberdog.analysis.readme_tables import readme_blocks
    assert readme_blocks(README)
    for name, block in readme_blocks(README).items():
        caption = README[:README.index(f"<!-- table:{name} -->")].rsplit("<!-- /table:", 1)[-1]
        assert f"--table {name}`" in caption, f"the README's {name} table does not say which command prints it"
        assert make_readme_tables.main(["--table", name]) == 0
        assert f"<!-- table:{name} -->\n{block}\n<!-- /table:{name} -->" in capsys.readouterr().out
