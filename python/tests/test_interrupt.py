"""Ctrl-C: SIGINT to a Python process running a longer scene in-process stops the run after the
batch under way, with an `interrupted` summary and complete outputs, as the command line does."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import ricochet
from conftest import ASSETS

SCRIPT = textwrap.dedent(
    """
    import sys, ricochet
    scene = ricochet.Scene.load(sys.argv[1]).set("run.end_time", 1.0)
    started = []
    def progress(t, end, steps):
        if not started:
            started.append(1)
            print("running", flush=True)
    result = scene.run(backend="cpu", out=sys.argv[2], progress=progress)
    print("status", result.status, flush=True)
    """
)


def test_sigint_leaves_an_interrupted_summary(tmp_path) -> None:
    out = tmp_path / "long"
    env = dict(os.environ, XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", "/tmp"))
    p = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, str(ASSETS / "rods_impact.toml"), str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        # A shell that started this suite in the background (`cmd &` without job control) left
        # SIGINT ignored, and Python then installs no Ctrl-C handler in the child: restore it.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        assert p.stdout is not None
        assert p.stdout.readline().strip() == "running"
        time.sleep(0.5)
        p.send_signal(signal.SIGINT)
        stdout, stderr = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0, stderr
    assert "status interrupted" in stdout
    assert "interrupted by SIGINT at step" in stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert summary["message"].startswith("interrupted by SIGINT at step")
    assert summary["end_time"] < 1.0
    r = ricochet.read(out)
    assert len(r.history) == summary["history_rows"]
