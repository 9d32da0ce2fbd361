"""ssn-shadow engine: soft shadows for 2D cutouts (SSN, Sheng et al., CVPR 2021).

Heavy modules load lazily so that the host kit (:mod:`ssn_engine.host_kit`:
the light map, the protocol, the client, the rules every front end shares)
imports without numpy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # for type checkers only: at run time __getattr__ imports it on first use
    from .api import predict_frames

__version__ = "0.2.0"
__all__ = ["__version__", "predict_frames"]


def __getattr__(name: str):
    if name == "predict_frames":
        from .api import predict_frames

        return predict_frames
    raise AttributeError(f"module 'ssn_engine' has no attribute {name!r}")
