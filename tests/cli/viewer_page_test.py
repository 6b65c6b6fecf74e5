"""Tests for mixstereo_tf.cli.viewer_page: the self-contained page, in a headless browser."""

import base64
import io
import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

from mixstereo_tf.cli import viewer_page

RED, GREEN, BLUE = (220, 30, 30), (30, 200, 30), (30, 30, 220)
SIZE = (40, 64)  # Every image's height, width: displayed at this size, one CSS px a pixel.


def _page(tmp_path):
  """A page whose mixture is red, left view green, right view blue, and whose other
  images hold none of those colours."""
  def plain(colour):
    return np.full(SIZE + (3,), colour, np.uint8)
  gray = plain((128, 128, 128))
  text = viewer_page.render('scene <1>', plain(GREEN), plain(BLUE), plain(RED), gray, gray,
                            [gray, gray], 110)
  path = tmp_path / 'scene_viewer.html'
  path.write_text(text, encoding='utf-8')
  return path, text


def _count(screenshot, colour):
  """Pixels of a screenshot within 40 levels of `colour` in every channel."""
  image = np.asarray(Image.open(screenshot).convert('RGB')).astype(int)
  return int((np.abs(image - np.array(colour)).max(axis=2) < 40).sum())


def _browser():
  for name in ('chromium', 'chromium-browser', 'google-chrome'):
    if shutil.which(name):
      return shutil.which(name)
  return None


def test_page_is_self_contained(tmp_path):
  _, text = _page(tmp_path)
  # No URL but data: URIs (base64 has no ':'), no CSS url() or @import: nothing is fetched.
  assert '://' not in text and re.search(r'(?i)https?:|url\(|@import|src="', text) is None
  assert '<title>scene &lt;1&gt;: recovered stereo pair</title>' in text
  assert text.count('data:image/jpeg;base64,') == 7  # 5 images, 2 synthesised views.


def test_images_carry_the_inputs_colour_profile_but_the_disparity_map(tmp_path):
  profile = b'a colour profile'  # Embedded as given: Pillow does not parse it.
  gray = np.full(SIZE + (3,), 128, np.uint8)
  text = viewer_page.render('p3', gray, gray, gray, gray, gray, [gray], 110, profile)
  images = json.loads(re.search(r'var IMAGES = (\{.*?\});', text).group(1))
  read = lambda uri: Image.open(io.BytesIO(base64.b64decode(uri.split(',', 1)[1])))
  for key, uri in images.items():
    assert read(uri).info.get('icc_profile') == (None if key == 'disparity' else profile), key


def test_slider_and_wiggle_change_the_picture_in_a_headless_browser(tmp_path):
  browser = _browser()
  if browser is None:
    print('no chromium found (apt-get install chromium): skipping the browser check')
    pytest.skip('chromium is not installed')
  path, _ = _page(tmp_path)
  counts = {}
  for name, fragment in (('input', 'slider=0&wiggle=1&frame=3'),
                         ('recovered', 'slider=100&wiggle=1&frame=0')):
    shot = tmp_path / f'{name}.png'
    # Networking off: every host resolves to nothing and every proxy is refused.
    subprocess.run([browser, '--headless=new', '--no-sandbox', '--disable-gpu',
                    '--hide-scrollbars', '--force-device-scale-factor=1',
                    '--host-resolver-rules=MAP * ~NOTFOUND', '--proxy-server=127.0.0.1:9',
                    '--disable-background-networking', '--window-size=400,300',
                    '--virtual-time-budget=2000', f'--screenshot={shot}',
                    f'{path.as_uri()}#{fragment}'],
                   check=True, capture_output=True, timeout=120)
    counts[name] = {c: _count(shot, colour) for c, colour in
                    (('red', RED), ('green', GREEN), ('blue', BLUE))}
  area = SIZE[0] * SIZE[1]
  # Slider at 0: the wipe shows the red input; wiggle frame 3 is the blue right view.
  assert counts['input']['red'] > 0.9 * area and counts['input']['blue'] > 0.9 * area
  assert counts['input']['green'] < 0.05 * area
  # Slider at 100: the green recovered left view; wiggle frame 0 is the green left view.
  assert counts['recovered']['green'] > 1.8 * area
  assert counts['recovered']['red'] < 0.05 * area and counts['recovered']['blue'] < 0.05 * area
