"""The dynamics tests' scene (test_dynamics.py, test_plot_animate.py): a small CCsub robot, 2
segments of 3 disks, tendon 1 stepped to 2 N within 10 ms."""

SCENE = {
    "model": "ccsub",
    "robot": {
        "backbone": {"density": 6450},
        "segments": [
            {"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
            {"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]},
        ],
    },
    "actuation": {"tensions": [0, 0, 0, 0]},
    "dynamics": {"bending_damping_time": 0.004},
    "timeline": [{"t": 0}, {"t": 0.01, "actuation": {"tensions": [2, 0, 0, 0]}}],
}
