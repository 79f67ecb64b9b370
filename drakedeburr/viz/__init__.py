"""drakedeburr.viz stage."""
