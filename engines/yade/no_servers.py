"""YADE's console and XML-RPC server never started: given to the launcher as
``yade -L engines.yade.no_servers ...`` (with the project's folder on PYTHONPATH), this module is
imported before YADE and makes ``yade.remote.runServers``, which the launcher calls before the
script's first line, do nothing. The project's own launches use it (engines.run.sweep.YADE);
every other ``yade`` process has its servers closed at the script's first line instead
(engines.yade.listeners). PORE_DEM_KEEP_YADE_SERVERS=1 keeps them here too. Imports nothing of
YADE itself: the launcher sets YADE's threads after it.
"""
import importlib.util
import os
import sys

from engines.yade.listeners import KEEP

MODULE = "yade.remote"


class _NoServers:
    """A finder that loads yade.remote as usual, then replaces its runServers."""

    def find_spec(self, name, path=None, target=None):
        if name != MODULE:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        load = spec.loader.exec_module

        def exec_module(module):
            load(module)
            module.runServers = lambda: None
        spec.loader.exec_module = exec_module
        return spec


if MODULE not in sys.modules and os.environ.get(KEEP) != "1":
    sys.meta_path.insert(0, _NoServers())
