"""Soft Shadow (SSN) for Krita: a docker that turns the selection or the active layer into a
soft shadow layer below it. All shadow logic runs in the ssn-shadow engine worker."""

try:
    from krita import DockWidgetFactory, DockWidgetFactoryBase, Krita
except ImportError:  # imported outside Krita (tests, the installer)
    Krita = None

if Krita is not None:
    from .docker import DOCKER_ID, SoftShadowDocker

    Krita.instance().addDockWidgetFactory(
        DockWidgetFactory(DOCKER_ID, DockWidgetFactoryBase.DockRight, SoftShadowDocker)
    )
