"""drakedeburr.path stage."""
