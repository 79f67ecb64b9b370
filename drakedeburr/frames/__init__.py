"""drakedeburr.frames stage."""
