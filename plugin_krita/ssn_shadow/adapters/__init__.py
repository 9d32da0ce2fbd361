"""Krita adapters: pixel formats, reading alpha, writing the shadow layer."""
