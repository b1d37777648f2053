"""The README's two commands are the project's contract with a new user; CI must run the second one."""
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def readme_commands():
    blocks = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)
    commands = [line for b in blocks[:2] for line in b.splitlines() if line and not line.startswith("#")]
    return commands


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
