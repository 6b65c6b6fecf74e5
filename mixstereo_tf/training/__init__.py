"""training package of mixstereo_tf."""
