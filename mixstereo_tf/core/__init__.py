"""The bottom floor: mixture operators, value ranges, worker counts, frame hints, the colour map. Imports nothing else of the package."""
