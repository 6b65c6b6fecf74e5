"""Both views of a mixture from its disparities: the encoding matrices solved per pixel, colour transfer, the Dubois leak."""
