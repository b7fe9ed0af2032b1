"""The `jit` decorator of the numerics, and where Numba keeps what it compiles of them.

Numba's cache normally sits beside a source file (in __pycache__), so each build's copy of this
package would be compiled again, for minutes. The copies are the same file in every build of one
andyc, so their cache is keyed by content instead: a cache locator (numba.core.caching) puts it
under ANDYC_CACHE_DIR, or else $XDG_CACHE_HOME/andyc (~/.cache/andyc), in a folder named after the
package, whose name carries the digest of its files (andyc_numerics_<digest>: the generated module
imports its copy by that name). Numba still checks each file's content hash (its source stamp)
and each function's bytecode, so an edited copy compiles afresh and never loads another's code.

Where that folder cannot be written, or Numba's cache API has changed, Numba's own locators apply
(the build's __pycache__). Without Numba, `jit` returns the function as it is: plain Python, slower.
Importing this module does not import Numba (andyc reads cache_folder() without it).
"""

import functools
import hashlib
import importlib.util
import os
import re
import warnings

NUMBA = importlib.util.find_spec("numba") is not None     # (imported on the first `jit`; none: plain Python)
PACKAGE = __name__.rpartition(".")[0]

# The model's functions reach the algorithms as first-class functions (model.py), which Numba calls
# experimental; they are the design here, so the warning on every compile would say nothing.
warnings.filterwarnings("ignore", message="First-class function type feature is experimental")


def cache_folder(package: str = PACKAGE) -> str:
    """Where Numba keeps what it compiles of the numerics package `package` (this one by default)."""
    root = os.environ.get("ANDYC_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "andyc")
    return os.path.join(root, package)


def jit(function=None, **options):
    """numba.njit, cached (by content, see above), with NumPy's error model (a division by zero gives
    inf or nan, as the checks for non-finite states expect, rather than raising)."""
    if not NUMBA:
        return function if function is not None else (lambda f: f)
    import numba

    _register_locator()
    decorate = numba.njit(cache=True, error_model="numpy", **options)
    return decorate(function) if function is not None else decorate


def cfunc(signature):
    """numba.cfunc of `signature`, cached (beside its file, or by content for this package's own), with
    NumPy's error model: a C callback, which compiled code can take as a first-class function."""
    import numba

    _register_locator()
    return numba.cfunc(signature, cache=True, error_model="numpy")


def _register_locator() -> None:
    """Put this package's cache in cache_folder(), once; where Numba's private cache API has changed, its own
    locators apply."""
    try:
        from numba.core import caching

        classes = caching.CacheImpl._locator_classes
        if any(getattr(c, "package", None) == PACKAGE for c in classes):
            return

        class ContentLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
            """The cache of this package's functions: in cache_folder(), checked by content."""
            package = PACKAGE

            def __init__(self, py_func, py_file):
                self._py_file = py_file
                self._lineno = py_func.__code__.co_firstlineno
                self._cache_path = cache_folder()

            def get_cache_path(self):
                return self._cache_path

            @classmethod
            def from_function(cls, py_func, py_file):
                if getattr(py_func, "__module__", "").rpartition(".")[0] != PACKAGE:
                    return None
                return super().from_function(py_func, py_file)     # None where the folder cannot be written

        classes.insert(0, ContentLocator)
    except (ImportError, AttributeError, TypeError):
        pass


@functools.lru_cache(maxsize=None)
def host_cpu() -> str:
    """The processor this machine's C leaves are compiled for (andyc/codegen/c_leaves.py compiles them with
    -march=native, as Numba compiles for the host): LLVM's name of it and a digest of its features, as
    Numba keys its own cache. A build's library carries it in its name (library_file), so that a build
    folder moved to, or shared with, another machine never loads instructions its processor may lack."""
    try:
        from llvmlite import binding

        name, features = binding.get_host_cpu_name(), binding.get_host_cpu_features().flatten()
    except Exception:       # no llvmlite (hence no Numba), or its API changed: the platform's and the kernel's words
        import platform

        name, features = platform.machine() or "cpu", platform.processor()
        try:
            with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
                features += next((line for line in fh if line.startswith("flags")), "")
        except OSError:
            pass
    digest = hashlib.sha256(features.encode()).hexdigest()[:8]
    return f"{re.sub(r'[^A-Za-z0-9]', '', name)[:24] or 'cpu'}-{digest}"


def library_file(stem: str) -> str:
    """The file name of a build's C leaves (<name>_leaves_<key16>, andyc/codegen/c_leaves.py) on this machine."""
    return f"{stem}_{host_cpu()}.so"
