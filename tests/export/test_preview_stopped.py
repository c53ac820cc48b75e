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
