"""The settings every front end starts from: the CLI, the Krita docker and the GIMP filter (stdlib only: the
plug-ins carry a copy)."""

OPACITY = 0.85  # the shadow layer's opacity
MAX_AO_STRENGTH = 4.0  # the contact (AO) strength scales the occlusion from 0 (none) to this
