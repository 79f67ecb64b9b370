"""drakedeburr.cell stage."""
