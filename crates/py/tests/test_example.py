"""examples/python/kanban.py runs without a display and draws its picture."""

import os
import subprocess
import sys


def test_kanban_example_draws_the_marginals(root, tmp_path):
    out = tmp_path / "marginal.png"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    env.pop("DISPLAY", None)
    p = subprocess.run(
        [sys.executable, str(root / "examples/python/kanban.py"), "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
    )
    assert p.returncode == 0, p.stderr
    assert "58,400 tangible markings" in p.stdout
    data = out.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 10_000
