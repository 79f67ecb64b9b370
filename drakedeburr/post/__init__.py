"""drakedeburr.post stage."""
