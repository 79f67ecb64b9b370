"""drakedeburr.hub stage."""
