"""ops package of mixstereo_tf."""
