# args: run {root}/scenarios/pick_place_camera.py -p camera_rate=1.5
# exit: 2
# expect: detection_rates of camera_slip_detector
"""A bad-input case: see tests/test_bad_inputs.py. A detection rate is a probability: 1.5 is refused."""
