"""The shared helpers of the cad/ scripts: joint paths and parameters (cadpaths), OCC
topology and seam sampling (cadocc), meshing at a tolerance (cadmesh), weldments (cadweldment)."""
