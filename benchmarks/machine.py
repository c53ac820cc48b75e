"""One line naming the conditions a benchmark ran under: numba threading layer and threads, load.

numba picks OpenMP when it is there (launch ≈ 2 µs, against ≈ 100 µs for its workqueue layer), but
OpenMP loses most of its speed when another process holds a core; a table is only comparable with
one taken under the same line. Call after the first parallel kernel ran (the layer is chosen then).
"""

import json
import os
import time


def conditions() -> str:
    import numba

    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel ran yet
        layer = "not chosen yet"
    return (
        f"numba threading layer {layer}, {numba.get_num_threads()} threads; "
        f"load average {os.getloadavg()[0]:.2f} (1 min) on {os.cpu_count()} cores"
    )


def stamp(load_at_start: float) -> dict[str, str]:
    """Where and when a measured row was taken (the fields every ``benchmarks/measured`` row carries): the load
    average from its start to now, the date, the cores."""
    return {
        "load": f"{load_at_start:.1f}–{os.getloadavg()[0]:.1f}",
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "machine": f"{os.cpu_count()} cores",
    }


def write_rows(path, rows: list[dict]) -> None:
    """Replace a ``benchmarks/measured`` file with ``rows``, one JSON line each (``tools/measured_tables.py``)."""
    path.write_text("".join(json.dumps(row, ensure_ascii=False) + "\n" for row in rows))
    print(f"wrote {path.relative_to(path.parents[2])}")
