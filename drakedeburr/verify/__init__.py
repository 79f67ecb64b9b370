"""drakedeburr.verify stage."""
