"""Observable properties for the docker's state, and two-way bindings of widgets to them.

A :class:`Property` on a ``QObject`` subclass stores one value per instance
and, when a new value differs from the old one, emits the class's
``<name>_changed`` signal (which the class declares) and calls the owner's
``_property_set(name)`` hook, where one exists. Read-only properties
(state the owner derives, shown but never edited) refuse plain assignment;
their owner sets them with :meth:`Property.set`.

:func:`bind` connects a widget to a property both ways: the widget shows the
property's value now and whenever it changes, and the widget's user edits set
the property. While it shows a value, the widget's own signal does not write
back, so showing a value never edits it (a slider that rounds a loaded value
does not change the setting).
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any, Generic, TypeVar, overload

from PyQt5.QtCore import QMetaObject, QObject

T = TypeVar("T")

__all__ = ["Binding", "Property", "bind"]


class Property(Generic[T]):
    """A value with a change signal.

    Parameters
    ----------
    default
        The value of a new instance (copied per instance).
    readonly
        Derived state: assignment raises ``AttributeError``; the owner uses :meth:`set`.
    """

    def __init__(self, default: T, readonly: bool = False) -> None:
        self.default, self.readonly = default, readonly
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, instance: None, owner: type | None = None) -> Property[T]: ...
    @overload
    def __get__(self, instance: object, owner: type | None = None) -> T: ...
    def __get__(self, instance: Any, owner: type | None = None) -> T | Property[T]:
        if instance is None:
            return self  # the class attribute is the descriptor
        values = instance.__dict__.setdefault("_property_values", {})
        if self.name not in values:
            values[self.name] = copy.deepcopy(self.default)
        return values[self.name]

    def __set__(self, instance: Any, value: T) -> None:
        if self.readonly:
            raise AttributeError(f"{self.name} is derived state: it is shown, not set")
        self.set(instance, value)

    def set(self, instance: Any, value: T) -> bool:
        """Store ``value``; emit ``<name>_changed`` and call the owner's hook if it differs. True if it did."""
        old = self.__get__(instance, type(instance))
        if old == value:
            return False
        instance.__dict__["_property_values"][self.name] = value
        getattr(instance, f"{self.name}_changed").emit(value)
        hook = getattr(instance, "_property_set", None)
        if hook is not None:
            hook(self.name)
        return True


class Binding:
    """The connections of one widget to one property; :meth:`disconnect` undoes them."""

    def __init__(self) -> None:
        self.connections: list[QMetaObject.Connection] = []
        self.showing = False

    def disconnect(self) -> None:
        for connection in self.connections:
            QObject.disconnect(connection)
        self.connections.clear()


def bind(
    model: QObject,
    name: str,
    show: Callable[[Any], None],
    edited: Any | None = None,
    write: Callable[..., None] | None = None,
) -> Binding:
    """Bind a widget to ``model``'s property ``name``.

    Parameters
    ----------
    model
        The object that owns the property (and its ``<name>_changed`` signal).
    name
        The property's name.
    show
        Shows a value in the widget (e.g. ``lambda v: slider.setValue(round(100 * v))``).
    edited
        The widget's signal for a user edit (e.g. ``slider.valueChanged``); None binds one way.
    write
        Sets the property from the signal's arguments (default: sets it to the first argument), e.g.
        ``lambda v: setattr(model, "opacity", v / 100)``.

    Returns
    -------
    Binding
        The connections, to disconnect when the widget shows another model.
    """
    binding = Binding()

    def to_widget(value: Any) -> None:
        binding.showing = True
        try:
            show(value)
        finally:
            binding.showing = False

    def to_model(*args: Any) -> None:
        if binding.showing:
            return
        if write is not None:
            write(*args)
        else:
            setattr(model, name, args[0])

    binding.connections.append(getattr(model, f"{name}_changed").connect(to_widget))
    to_widget(getattr(model, name))
    if edited is not None:
        binding.connections.append(edited.connect(to_model))
    return binding
