"""baselines package of mixstereo_tf."""
