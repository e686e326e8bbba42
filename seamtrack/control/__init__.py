"""Control: the robot (the paper's Cartesian gantry), the tracker protocol and the built-in
trackers."""
