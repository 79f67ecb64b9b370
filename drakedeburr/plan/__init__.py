"""drakedeburr.plan stage."""
