"""Multi-pass jobs: a scan, then pass after pass, each planned from the groove the pass before
measured, tracked in the closed loop and deposited as a bead (the job, where a pass aims, the
paths and grooves it measures, the summary and inspection); the planners themselves are in
:mod:`seamtrack.control.planner`."""
