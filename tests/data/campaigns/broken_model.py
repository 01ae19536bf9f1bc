"""A model file that fails on import (for bad_python_module_error.yaml)."""
raise ImportError("numpy.linalg.lapack_lite is missing (a broken install, on purpose)")
