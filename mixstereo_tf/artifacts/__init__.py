"""What a run leaves and what ships: runs, SavedModel export and serving graphs, shipped models."""
