"""data package of mixstereo_tf."""
