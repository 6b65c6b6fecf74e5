"""Support for the command-line tools: quiet start-up and the flags they share."""
