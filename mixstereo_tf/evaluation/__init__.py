"""evaluation package of mixstereo_tf."""
