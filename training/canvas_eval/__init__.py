"""Canvas-scale evaluation of shadows under disk lights: truth renders, metrics and the scoring command."""
