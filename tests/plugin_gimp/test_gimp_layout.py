"""The dialog's layout for the screen it opens on (ssn_layout), without GIMP (issue item d).

The sizes are the real dialog's under Xvfb (test_gimp_dialog_controls.py measures them): side by side 850 x 690
pixels for a landscape image, stacked 454 x 1110.
"""

from ssn_layout import FRAME, Layout, choose_layout

SIDE, STACKED = (850, 690), (454, 1110)


def test_side_by_side_where_it_fits():
    assert choose_layout(SIDE, STACKED, (1366, 768)) == Layout(stacked=False)
    assert choose_layout(SIDE, STACKED, (1920, 1080)) == Layout(stacked=False)


def test_stacked_on_a_portrait_screen():
    """768 x 1366: side by side, OK lay past the right edge; stacked, the dialog fits."""
    assert choose_layout(SIDE, STACKED, (768, 1366)) == Layout(stacked=True)
    assert choose_layout(SIDE, STACKED, (SIDE[0] + FRAME[0] - 1, 1366)).stacked  # a pixel too narrow
    assert not choose_layout(SIDE, STACKED, (SIDE[0] + FRAME[0], 1366)).stacked


def test_scrolled_where_neither_fits():
    """Too short for side by side (a panel on a 1366 x 720 work area) with room across: side by side, scrolling;
    too small for either: stacked, scrolling, within the work area less the frame."""
    short = choose_layout(SIDE, STACKED, (1366, 700))
    assert short == Layout(stacked=False, scrolled=True, max_width=1366 - FRAME[0], max_height=700 - FRAME[1])
    small = choose_layout(SIDE, STACKED, (600, 800))
    assert small == Layout(stacked=True, scrolled=True, max_width=600 - FRAME[0], max_height=800 - FRAME[1])
