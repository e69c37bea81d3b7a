"""Shared fixtures: the repository, and the `petrinav` command line that the
Python results are compared with.

The command line is `$PETRINAV_BIN` when set — `scripts/test` sets it to
the binary `cargo test --workspace` has just built, `target/debug/petrinav`
(the numbers are the same bits in every profile: no fast-math) —;
otherwise it is built with `cargo build --release -p petrinav` once per
session (a no-op when it is up to date; on a fresh clone a few minutes:
its dependencies' features unify differently from the Python package's, so
little of what `pip install ./crates/py` compiled is reused).
"""

import json
import os
import subprocess
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]

# pm4py prints a banner and warns about missing final markings: not ours.
warnings.filterwarnings("ignore", module="pm4py")


def _target_dir() -> Path:
    env = os.environ.get("CARGO_TARGET_DIR")
    return Path(env) if env else ROOT / "target"


@pytest.fixture(scope="session")
def root() -> Path:
    """The repository's root."""
    return ROOT


@pytest.fixture(scope="session")
def cli_bin() -> Path:
    """The `petrinav` binary (see the module docs)."""
    env = os.environ.get("PETRINAV_BIN")
    if env:
        return Path(env)
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "-p", "petrinav"],
        cwd=ROOT,
        check=True,
    )
    return _target_dir() / "release" / "petrinav"


class Cli:
    """Runs the command line from the repository's root."""

    def __init__(self, binary: Path):
        self.binary = binary

    def run(self, *args, check=True) -> subprocess.CompletedProcess:
        p = subprocess.run(
            [str(self.binary), *map(str, args)],
            cwd=ROOT,
            capture_output=True,
            text=True,
        )
        if check and p.returncode != 0:
            raise AssertionError(f"petrinav {' '.join(map(str, args))} failed:\n{p.stderr}")
        return p

    def json(self, *args):
        """The command's `--json` output, parsed."""
        return json.loads(self.run(*args, "--json").stdout)

    def json_lines(self, *args):
        """The command's `--json` output, one object per line."""
        out = self.run(*args, "--json").stdout
        return [json.loads(line) for line in out.splitlines() if line.strip()]

    def error(self, *args) -> str:
        """The message the command prints after `error: ` (it must fail)."""
        p = self.run(*args, check=False)
        assert p.returncode != 0, f"petrinav {' '.join(map(str, args))} succeeded"
        lines = [l for l in p.stderr.splitlines() if l.startswith("error: ")]
        assert lines, p.stderr
        return lines[-1][len("error: "):]


@pytest.fixture(scope="session")
def cli(cli_bin) -> Cli:
    return Cli(cli_bin)


@pytest.fixture(scope="session")
def kanban_pnpro(tmp_path_factory, cli) -> Path:
    """Kanban as a GreatSPN file with its parameter N (written by the CLI)."""
    path = tmp_path_factory.mktemp("nets") / "kanban.pnpro"
    cli.run("gspn", "family", "kanban", "1", "-o", path)
    return path


def close(a: float, b: float, tol: float = 1e-12) -> bool:
    """Equal to `tol`, absolutely and relatively."""
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))
