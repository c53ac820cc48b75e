"""A ``--plugin`` file for tests that stop a run as a finished step is stored: it makes ``Cache.store`` of the node
``$SLOW_STORE_NODE`` write a file named after its process in ``$SLOW_STORE_STARTED`` (from then on the step is being
stored), then take ``$SLOW_STORE_S`` seconds. It declares no node."""

import os
import time
from pathlib import Path

from nodegraph.cache import Cache

_store = Cache.store


def _slow_store(self, key, outputs, node_id, *args, **kwargs):
    if node_id == os.environ.get("SLOW_STORE_NODE"):
        folder = Path(os.environ["SLOW_STORE_STARTED"])
        folder.mkdir(parents=True, exist_ok=True)
        (folder / str(os.getpid())).touch()
        time.sleep(float(os.environ.get("SLOW_STORE_S", "2")))
    return _store(self, key, outputs, node_id, *args, **kwargs)


Cache.store = _slow_store
