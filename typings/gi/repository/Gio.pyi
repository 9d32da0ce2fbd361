"""GObject-introspection namespace Gio (untyped: generated from its typelib at run time)."""

from typing import Any

def __getattr__(name: str) -> Any: ...
