"""
# A synthetic profile through an extractor

`synthetic_profile` draws the stripe a sensor would measure on an analytic joint, with its
exact seam point; an extractor then finds the seam point from the profile alone. Here a
60 deg V-groove, tilted, with range noise, 5 % outliers and a false reflection.
"""

import matplotlib.pyplot as plt
import numpy as np

import seamtrack as st
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.sensor import preset
from seamtrack.viz.plots import draw_profile_2d

sensor = preset("paper")
profile, truth = synthetic_profile(
    "v-groove",
    sensor,
    rng=np.random.default_rng(0),
    pitch_deg=10,
    roll_deg=-5,
    lateral_offset_mm=1.0,
    imperfections=Imperfections(noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0),
    included_angle_deg=60,
    gap_mm=1.0,
    root_face_mm=1.0,
)
feature = st.extractor("v-groove")(profile)
error = np.hypot(*(feature.point_laser - truth.seam_laser))
print(f"found: {bool(feature)}, {error:.4f} mm from the true seam point")

# %%
fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
draw_profile_2d(ax, profile, truth=truth, feature=feature)
plt.show()
