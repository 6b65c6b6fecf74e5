"""Training-free classical baselines for de-anaglyph and de-diplopia.

Stand-ins for the paper's classical comparisons (Joulin & Kang 2013, Williem et al. 2015),
which have no public code: `anaglyph.unmix_anaglyph` (census-SGM across colour channels
over a signed range, and the matrix-driven restoration of both views, for every anaglyph
encoding) and `diplopia.unmix_diplopia` (self-matching of the double image and
least-squares layer separation; disparities positive by convention). Which one serves a
mixture, with which range and options, is its family's choice
(`mixstereo_tf.unmixing.families`).
"""
