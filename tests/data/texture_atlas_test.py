"""Tests of the texture atlas: the bundled splits, mirrored lookups, a photo folder."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.data import texture_atlas


def _constant(value):
  return np.full((4, 4, 3), value, np.float32)


def test_texture_splits_are_disjoint_and_load_offline():
  splits = texture_atlas.TEXTURE_SPLITS
  assert not set(splits['train']) & set(splits['heldout'])
  for split in ('train', 'heldout'):
    atlas = texture_atlas.load_textures(split)
    assert len(atlas) == len(splits[split])
    assert atlas.image.dtype == np.float32 and atlas.image.shape[-1] == 3
    assert atlas.image.std() > 10.0  # Real texture, not a blank placeholder.
  with pytest.raises(ValueError, match='valid'):
    texture_atlas.load_textures('test')


def test_atlas_lookup_mirrors_out_of_range_coordinates():
  image = np.arange(2 * 5 * 3, dtype=np.float32).reshape(2, 5, 3)
  atlas = texture_atlas.TextureAtlas([_constant(9), image])
  index = np.ones((1, 4), np.int32)
  u = np.array([[1.0, -1.0, 5.0, 2.5]], np.float32)  # reflect-101: -1 -> 1, 5 -> 3.
  v = np.zeros((1, 4), np.float32)
  got = atlas.lookup(index, u, v)[0]
  np.testing.assert_allclose(got, [image[0, 1], image[0, 1], image[0, 3],
                                   (image[0, 2] + image[0, 3]) / 2])


def test_texture_dir_reduces_and_skips_unreadable_files(tmp_path):
  image = np.zeros((40, 100, 3), np.uint8)
  image[..., 2] = 200  # Red in OpenCV's BGR order.
  cv2.imwrite(str(tmp_path / 'a.png'), image)
  (tmp_path / 'broken.jpg').write_bytes(b'not an image')
  (tmp_path / 'notes.txt').write_text('ignored')
  atlas = texture_atlas.load_texture_dir(str(tmp_path), sigma=0.0, long_side=50)
  assert len(atlas) == 1
  np.testing.assert_array_equal(atlas.sizes, [[20, 50]])
  np.testing.assert_allclose(atlas.image[5, 5], [200, 0, 0])  # Read as RGB.
  empty = tmp_path / 'empty'
  empty.mkdir()
  with pytest.raises(ValueError, match='No readable image'):
    texture_atlas.load_texture_dir(str(empty))
