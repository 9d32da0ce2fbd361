"""Qt widgets of the Soft Shadow docker."""
