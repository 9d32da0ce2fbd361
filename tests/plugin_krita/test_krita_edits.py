"""The docker in a real Krita window after edits made outside it: the cutout painted on, a step chosen in the
Undo History docker, a document closed (kritarunner under xvfb-run; the docker built by Krita from its factory)."""

import pytest
from krita_helpers import run_in_fresh_profile

pytestmark = pytest.mark.krita


def test_the_docker_follows_edits_made_outside_it(tmp_path):
    data = run_in_fresh_profile(tmp_path, "krita_edits_driver")

    # the cutout's lower half erased after Generate: the light change casts the shadow Generate casts from the
    # layer as it is now, not the old cutout's; so does a drag's release after more alpha was painted
    stale = data["stale"]
    assert stale["whole"] is not None and stale["by_light"] != stale["whole"], stale
    assert stale["by_light"] == stale["by_generate"], stale
    assert stale["dragged"] == stale["dragged_by_generate"], stale
    assert stale["messages"][0] == "info", stale
    # the worker's cutout: a new one after the erase, read again by the light change (not by Generate); the same
    # after the drag's release as after the Generate that follows it
    keys = stale["keys"]
    assert keys[1] != keys[0] and keys[1] == keys[2], stale
    assert stale["drag_keys"][0] == stale["drag_keys"][1] != keys[2], stale

    # two steps back in the Undo History docker bring the previous shadow layer back, which Krita activates:
    # the cutout's layer is active again; and two steps forward
    history = data["history"]
    assert history["back"]["shadow_changed"], history
    assert history["back"]["active"] == "Person", history
    assert history["forward"]["shadow_is_last"] and history["forward"]["active"] == "Person", history

    # a document whose message the docker showed, closed (its window's last view): the message goes
    closing = data["closing"]
    assert "RGB/Alpha" in closing["message_before"], closing
    assert "ssn-grey" not in closing["open_documents"], closing
    assert closing["message_after"] != closing["message_before"], closing
