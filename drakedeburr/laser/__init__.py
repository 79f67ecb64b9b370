"""drakedeburr.laser stage."""
