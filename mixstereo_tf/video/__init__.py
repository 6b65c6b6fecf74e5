"""Video: decoding and encoding with audio, the per-file job, the temporal prior."""
