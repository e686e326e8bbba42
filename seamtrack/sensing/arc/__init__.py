"""The welding arc in the sensor's view: the arc's light through the camera's band-pass
filter, the plate it lights and heats, spatter and fume, drawn into images; and the cheap
statistical model of what they do to a profile (false points, drop-outs) for scenes that form
no image. A scene's ``[arc]`` section (:class:`seamtrack.simulation.config.ArcConfig`) turns
it on; docs/arc.md is the manual."""
