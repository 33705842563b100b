"""Where numba keeps the compiled kernels: a folder keyed by the sources it compiled and numba's version.

numba's own cache (``cache=True``) checks only the timestamp and size of the file that defines a
kernel and freezes the globals it reads (the layouts of engines.compiled.layout, the constants of
engines.model) into the machine code: a kernel whose callee or layout lives in another module would
run stale code after an edit there. So the cache folder (NUMBA_CACHE_DIR, set by
engines/compiled/__init__.py before numba compiles anything) is keyed by ``cache_key``: a hash of
every .py file of engines/model and engines/compiled (their paths and contents, sorted), of
numba's version and of the checkout's folder (numba names its own subfolders by the sources' path,
so a second checkout of the same code finds nothing compiled for it: its own key makes its warm-up
run and its first run say that it compiles). Any edit there, or another numba, compiles afresh into a new folder; going back to
earlier sources finds their folder again while it is among the KEEP most recently used (older
keyed folders are removed when a new one is made).

The folder is ``cache_dir()``: <root>/<key>, the root being the user's own NUMBA_CACHE_DIR if one
was set, else the first writable of ~/.cache/pore-dem/numba (XDG_CACHE_HOME), <project>/.numba-cache
and the system's temporary folder. An install's warm-up compiles into the same folder.
"""
import hashlib
import importlib.metadata
import os
import shutil
import sys
import tempfile

ENGINES = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCES = ("model", "compiled")  # the packages of engines/ whose code the kernels compile
KEYED = "PORE_DEM_NUMBA_CACHE_DIR"  # the keyed folder this module set as NUMBA_CACHE_DIR (for child processes)
KEEP = 8  # keyed folders kept under a root (about 20 MB each), the most recently used
COMPILE_SECONDS = 60  # [s] about what compiling the kernels a scene uses takes (2 shared cores, 2026-12-04)
fresh = False  # use() found its keyed folder holding no compiled kernel: the next run compiles them


def cache_key(engines=ENGINES):
    """The hex key (16 digits) of the kernels' sources (those of the engines/ folder ``engines``),
    where they are, and numba's version."""
    h = hashlib.sha256(f"numba {importlib.metadata.version('numba')}\n{os.path.abspath(engines)}\n".encode())
    for package in SOURCES:
        root = os.path.join(engines, package)
        for folder, dirs, files in os.walk(root):
            dirs[:] = sorted(d for d in dirs if d != "__pycache__")
            for name in sorted(f for f in files if f.endswith(".py")):
                path = os.path.join(folder, name)
                with open(path, "rb") as f:
                    data = f.read()
                h.update(f"{os.path.relpath(path, engines)} {len(data)}\n".encode())
                h.update(data)
    return h.hexdigest()[:16]


def _roots(environ):
    """The candidate roots of the keyed folder, first choice first."""
    own = environ.get("NUMBA_CACHE_DIR", "")
    if own and own == environ.get(KEYED):  # keyed by a parent process of this project: its root
        own = os.path.dirname(own)
    if own:
        return [own]
    xdg = environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return [os.path.join(xdg, "pore-dem", "numba"), os.path.join(os.path.dirname(ENGINES), ".numba-cache"),
            os.path.join(tempfile.gettempdir(), f"pore-dem-numba-{os.getuid()}")]


def cache_dir(environ=None):
    """The keyed folder numba caches the kernels in (made if missing): <root>/<cache_key()> under
    the first writable root (module docstring), or None when none is writable (numba then caches
    in its own places, beside the sources, checked by their timestamps only)."""
    key = cache_key()
    for root in _roots(os.environ if environ is None else environ):
        path = os.path.join(root, key)
        try:
            os.makedirs(path, exist_ok=True)
        except OSError:
            continue
        if os.access(path, os.W_OK | os.X_OK):
            os.utime(path)  # used now
            _prune(root)
            return path
    return None


def _prune(root):
    """Remove the keyed folders under root beyond the KEEP most recently used (any other folder is left)."""
    keyed = [e for e in os.scandir(root) if e.is_dir(follow_symlinks=False) and len(e.name) == 16
             and all(c in "0123456789abcdef" for c in e.name)]
    keyed.sort(key=lambda e: e.stat().st_mtime, reverse=True)
    for e in keyed[KEEP:]:
        shutil.rmtree(e.path, ignore_errors=True)


def is_empty(path):
    """Does the folder ``path`` hold no file (in any of its subfolders)?"""
    for entry in os.scandir(path):
        if entry.is_file(follow_symlinks=False) or entry.is_dir(follow_symlinks=False) and not is_empty(entry.path):
            return False
    return True


def compile_note():
    """The line a run says before it compiles the kernels afresh, or None when ``use`` found
    compiled kernels."""
    if fresh:
        return f"compiling the numba kernels (about {COMPILE_SECONDS} s, once per version of the code)..."
    return None


def use():
    """Point numba at ``cache_dir()`` (NUMBA_CACHE_DIR, marked for child processes in KEYED),
    numba's configuration read again if it was loaded already. Returns the folder (None: none writable)."""
    global fresh
    path = cache_dir()
    if path is None:
        return None
    fresh = is_empty(path)
    os.environ["NUMBA_CACHE_DIR"] = os.environ[KEYED] = path
    config = sys.modules.get("numba.core.config")
    if config is not None:  # numba imported before this package: its settings taken from the environment again
        config.reload_config()
    return path
