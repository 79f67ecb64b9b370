"""drakedeburr.orientation stage."""
