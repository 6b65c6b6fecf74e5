"""A census matching-cost volume in TensorFlow (XLA-safe), the classical matcher's cost.

Census (Zabih & Woodfill 1994) encodes each pixel by which of its window neighbours are
darker than it; the Hamming distance between two codes is a matching cost that ignores the
images' gains and offsets, which is why the classical de-anaglyph can compare a red channel
with a green one. `cost_volume` gives the stereo network that cost beside its learned
features (`ModelConfig.census_cost`): the network then learns to aggregate it.

Sign convention (docs/DESIGN.md): slice d compares the left pixel x with the right pixel
x - d; where x - d < 0 there is no match and the cost is 0.5 (as likely as not).
"""

import tensorflow as tf

# 7 x 9 window: 62 comparisons, packed 31 per int32 word (the sign bit stays unused).
WINDOW = (7, 9)
_PER_WORD = 31


def _luma(image: tf.Tensor) -> tf.Tensor:
  r, g, b = image[..., 0], image[..., 1], image[..., 2]
  return 0.299 * r + 0.587 * g + 0.114 * b


def census_codes(image: tf.Tensor) -> tf.Tensor:
  """Census codes of the luminance of a batch of RGB images.

  Args:
    image: [B, H, W, 3] float (any range); borders are reflected.

  Returns:
    int32 [B, H, W, 2]: bit k set where the k-th neighbour of the 7x9 window (centre
    excluded, row-major) is darker than the centre; 31 bits per word.
  """
  luma = _luma(tf.cast(image, tf.float32))
  ry, rx = WINDOW[0] // 2, WINDOW[1] // 2
  padded = tf.pad(luma, [[0, 0], [ry, ry], [rx, rx]], mode='REFLECT')
  height, width = tf.shape(luma)[1], tf.shape(luma)[2]
  words = [tf.zeros_like(luma, tf.int32), tf.zeros_like(luma, tf.int32)]
  bit = 0
  for dy in range(WINDOW[0]):
    for dx in range(WINDOW[1]):
      if (dy, dx) == (ry, rx):
        continue
      darker = tf.cast(padded[:, dy:dy + height, dx:dx + width] < luma, tf.int32)
      word, position = divmod(bit, _PER_WORD)
      words[word] = tf.bitwise.bitwise_or(words[word], tf.bitwise.left_shift(darker, position))
      bit += 1
  return tf.stack(words, axis=-1)


def cost_volume(left: tf.Tensor, right: tf.Tensor, num_disparities: int) -> tf.Tensor:
  """Census Hamming costs of a rectified pair for disparities 0 .. D - 1.

  Args:
    left, right: [B, H, W, 3] images (the same range for both).
    num_disparities: D.

  Returns:
    float32 [B, D, H, W, 1] in [0, 1]: the Hamming distance / 62 between the left code at x
    and the right code at x - d; 0.5 where x - d < 0.
  """
  if num_disparities <= 0:
    raise ValueError(f'num_disparities must be positive, got {num_disparities}.')
  codes_left, codes_right = census_codes(left), census_codes(right)
  width = tf.shape(codes_left)[2]
  bits = float(WINDOW[0] * WINDOW[1] - 1)
  padded = tf.pad(codes_right, [[0, 0], [0, 0], [num_disparities - 1, 0], [0, 0]])
  columns = tf.range(width)
  slices = []
  for d in range(num_disparities):
    shifted = padded[:, :, num_disparities - 1 - d:num_disparities - 1 - d + width, :]
    distance = tf.reduce_sum(tf.cast(tf.raw_ops.PopulationCount(
        x=tf.bitwise.bitwise_xor(codes_left, shifted)), tf.float32), axis=-1) / bits
    slices.append(tf.where((columns >= d)[None, None, :], distance, 0.5))
  return tf.stack(slices, axis=1)[..., None]
