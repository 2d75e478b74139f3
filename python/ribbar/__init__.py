"""ribbar from Python: rib-scale steel-concrete bond simulations.

    import ribbar
    result = ribbar.run("specs/r1-coarse.yaml", set={"bar.ribs.angle": "60 deg"})
    result.curve            # DataFrame, SI; units in result.curve.attrs["units"]
    result.summary          # summary.json as a dict
    result.field("peak")    # meshio mesh of the peak's fields

The stages, their cache and their outputs are the `ribbar` command line's
(bundled in this package); this module runs it and reads what it writes.
"""

from typing import TYPE_CHECKING, Any

from ribbar._native import __version__

__all__ = [
    "BOND_LAW_UNITS",
    "CURVE_UNITS",
    "MATERIAL_UNITS",
    "FieldFiles",
    "Result",
    "RibbarError",
    "Status",
    "StudyResult",
    "__version__",
    "load",
    "material",
    "run",
    "study",
]

if TYPE_CHECKING:
    from ribbar._api import (
        BOND_LAW_UNITS,
        CURVE_UNITS,
        MATERIAL_UNITS,
        FieldFiles,
        Result,
        RibbarError,
        Status,
        StudyResult,
        load,
        material,
        run,
        study,
    )


def __getattr__(name: str) -> Any:
    # pandas is imported on first use of the API, not by the `ribbar`
    # command (`python -m ribbar`), whose start-up a cached run waits for.
    if name in __all__:
        from ribbar import _api

        return getattr(_api, name)
    raise AttributeError(f"module 'ribbar' has no attribute {name!r}")
