"""``nodegraph watch`` stops a preview that a save made obsolete with SIGINT to the main thread (``WatchSession``),
which relies on Mitsuba answering it by cancelling its render: the render must stop at once, not run to its end,
and the process must still render afterwards."""

import signal
import threading
import time

import pytest

from nodes.export import preview


def _render(scene, **over):
    return preview.call(scene=scene, **{"width": 64, "height": 48, "samples": 2, **over}).pixels


def test_a_preview_stopped_by_sigint_stops_at_once_and_the_process_renders_on(shaded, capfd):
    _render(shaded)  # loads Mitsuba and the scene's code: what follows times the render alone
    # the watch installs its own SIGINT handler; so does this test: a suite started in the background of a
    # non-interactive shell inherits SIGINT ignored, and Mitsuba then winds its render down without an exception
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _stop_a_render(shaded)
    finally:
        signal.signal(signal.SIGINT, previous)
    after = _render(shaded)
    assert after.shape == (48, 64, 3) and after.any()
    # Mitsuba's own note of the interrupt stays out of the run's output (issue 47), its other messages do not
    import mitsuba as mi

    mi.Log(mi.LogLevel.Warn, "a warning of Mitsuba's own")
    said = "".join(capfd.readouterr())
    assert "Received interrupt signal" not in said and "a warning of Mitsuba's own" in said, said


def _stop_a_render(shaded):
    main = threading.main_thread().ident
    timer = threading.Timer(1.0, lambda: signal.pthread_kill(main, signal.SIGINT))
    started = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        _render(shaded, width=1280, height=720, samples=256)  # minutes of path tracing if not stopped
    stopped = time.perf_counter() - started
    assert stopped < 10.0, f"the render took {stopped:.1f} s to stop"


LOADS_NOTHING = """
import sys
from pathlib import Path

from nodegraph import codec
from nodes.export import preview as node
from nodes.export.preview import load_libraries

scene = codec.decode(Path(sys.argv[1]).read_bytes())  # as a run with its upstream cached has it: nothing else loaded
load_libraries()
before = {n for n, m in sys.modules.items() if str(getattr(m, "__file__", "")).endswith(".so")}
node.call(scene=scene, width=32, height=24, samples=1)
print(sorted({n for n, m in sys.modules.items() if str(getattr(m, "__file__", "")).endswith(".so")} - before))
"""


def test_a_preview_loads_no_library_after_its_overlap_step(shaded, tmp_path):
    """A run computes other steps (the export: USD) beside the preview once its ``overlap`` step has run; a native
    library the render loaded after that could deadlock against the other thread's (the loader's lock against the
    GIL): a run with its upstream cached hung for good, the preview importing SciPy's spatial module (issue 47)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    from nodegraph import codec

    (tmp_path / "scene.bin").write_bytes(codec.encode(shaded))
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run(
        [sys.executable, "-c", LOADS_NOTHING, str(tmp_path / "scene.bin")],
        cwd=root,
        env={**os.environ, "PYTHONPATH": str(root)},
        capture_output=True,
        text=True,
        check=True,
    )
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout


def test_the_export_declares_every_usd_module_its_writer_imports():
    """A run loads the export's ``libraries`` in the main thread before the export runs beside the preview: each pxr
    module ``usd_writer`` imports is loaded by then, so USD never opens a library in the export's thread while the
    render may open one (a run of the onigiri hung so, USD holding the loader's lock and waiting for the GIL)."""
    import re
    import sys
    from pathlib import Path

    from nodes.export import usd_writer

    source = Path(usd_writer.__file__).read_text()
    functions = source.split("def load_libraries", 1)[1].split("\ndef ", 1)[1]  # the writer, past the loader
    used = {name.strip() for names in re.findall(r"from pxr import ([\w, ]+)", functions) for name in names.split(",")}
    assert used, "usd_writer imports no pxr module: this test reads nothing"
    import subprocess

    # in a process of its own: a test before this one in the same worker may have loaded pxr already
    probe = "import sys; from nodes.export import export; export.libraries(); print(*sorted(sys.modules))"
    root = Path(__file__).resolve().parents[2]
    loaded = subprocess.run(
        [sys.executable, "-c", probe], cwd=root, capture_output=True, text=True, check=True
    ).stdout.split()
    missing = sorted(name for name in used if f"pxr.{name}" not in loaded)
    assert not missing, f"the export's libraries leave {missing} for the export's thread to load"
