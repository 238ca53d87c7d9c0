"""Which people's trials `casa calibrate` reads: a continuous device's are left out."""

from casa_core.calibration import design


def test_a_device_trial_is_left_out_naming_the_device_and_a_keyboard_trial_is_kept():
    meta = {"phase": "no_misspecification", "flags": []}
    assert design._left_out(meta) is None
    assert design._left_out({**meta, "input": "keyboard"}) is None
    why = design._left_out({**meta, "input": "spacemouse"})
    assert why is not None and why.startswith("driven with a spacemouse")
