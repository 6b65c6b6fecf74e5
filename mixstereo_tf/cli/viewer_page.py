"""A self-contained HTML page to look at one recovered stereo pair (`--output_format=html`).

No server and no network: every image is embedded as a base64 JPEG data URI, the CSS and
the script are inline and the page names no external URL. It shows
- before / after: the recovered left view over the input mixture, a slider wiping from one
  to the other (0: all input, 100: all recovered);
- the pair cross-eyed (right view first), parallel, or as a re-encoded Dubois anaglyph (a
  switch), and a wiggle toggle cycling left -> synthesised views -> right -> back;
- the colour-mapped disparity.

The URL fragment sets the state, so a link (or a headless browser) opens the page as
wanted: `#slider=0..100&view=cross|parallel|anaglyph&wiggle=1&frame=K`, where `frame`
holds the wiggle on frame K of its cycle instead of animating it.
"""

import base64
import html
import io
import json
import string
from typing import Optional, Sequence

import numpy as np
from PIL import Image

EMBED_QUALITY = 90  # JPEG quality of the embedded images.

_PAGE = string.Template('''<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>$title: recovered stereo pair</title>
<style>
body{margin:0;padding:10px;background:#1e1e1e;color:#ddd;font:13px sans-serif}
h1{font-size:15px;margin:0 0 6px}
section{margin:0 0 10px}
.row{display:flex;gap:14px;flex-wrap:wrap;align-items:flex-start}
.controls{margin:4px 0}
button{background:#333;color:#ddd;border:1px solid #555;padding:2px 9px;cursor:pointer}
button.on{background:#4a6fa5;color:#fff}
.wipe{position:relative;display:inline-block;line-height:0}
.wipe img{display:block;max-width:100%}
#after{position:absolute;left:0;top:0;width:100%;height:100%}
#divider{position:absolute;top:0;width:2px;height:100%;margin-left:-1px;background:#fff}
#slider{display:block;width:100%;margin:4px 0 0}
.pair{display:flex;gap:6px;line-height:0}
.pair img{display:block;max-width:calc(50% - 3px)}
.pair.single img{max-width:100%}
</style></head><body>
<h1>$title</h1>
<div class="row">
<section><div class="controls">Recovered left view | input</div>
<div class="wipe"><img id="before" alt="input"><img id="after" alt="recovered left view">
<div id="divider"></div></div>
<input type="range" id="slider" min="0" max="100" value="50"></section>
<section><div class="controls">Disparity (left view)</div>
<img id="disparity" alt="disparity"></section>
</div>
<section><div class="controls"><button data-view="cross">cross-eyed</button>
<button data-view="parallel">parallel</button><button data-view="anaglyph">anaglyph</button>
<label><input type="checkbox" id="wiggle"> wiggle</label></div>
<div class="pair" id="pair"><img id="first" alt="view"><img id="second" alt="view"></div>
</section>
<script>
var IMAGES = $images;
var BETWEEN = $between;
var FRAME_MS = $frame_ms;
(function () {
  var VIEWS = ['cross', 'parallel', 'anaglyph'];
  var CYCLE = [IMAGES.left].concat(BETWEEN, [IMAGES.right], BETWEEN.slice().reverse());
  var state = {slider: 50, view: 'cross', wiggle: false, frame: -1};
  var timer = null;
  function el(id) { return document.getElementById(id); }
  function readHash() {
    var params = new URLSearchParams(location.hash.slice(1));
    var slider = Number(params.get('slider'));
    if (params.has('slider') && isFinite(slider)) {
      state.slider = Math.max(0, Math.min(100, slider));
    }
    if (VIEWS.indexOf(params.get('view')) >= 0) state.view = params.get('view');
    if (params.has('wiggle')) state.wiggle = params.get('wiggle') === '1';
    var frame = parseInt(params.get('frame'), 10);
    state.frame = isFinite(frame) ? ((frame % CYCLE.length) + CYCLE.length) % CYCLE.length : -1;
  }
  function drawSlider() {
    el('slider').value = state.slider;
    el('after').style.clipPath = 'inset(0 ' + (100 - state.slider) + '% 0 0)';
    el('divider').style.left = state.slider + '%';
  }
  function show(first, second) {
    el('first').src = first;
    el('second').style.display = second ? '' : 'none';
    if (second) el('second').src = second;
    el('pair').className = second ? 'pair' : 'pair single';
  }
  function drawPair() {
    clearInterval(timer);
    timer = null;
    el('wiggle').checked = state.wiggle;
    var buttons = document.querySelectorAll('button[data-view]');
    for (var i = 0; i < buttons.length; i++) {
      var on = !state.wiggle && buttons[i].getAttribute('data-view') === state.view;
      buttons[i].className = on ? 'on' : '';
    }
    if (state.wiggle) {
      var shown = state.frame >= 0 ? state.frame : 0;
      show(CYCLE[shown]);
      if (state.frame < 0) {
        timer = setInterval(function () {
          shown = (shown + 1) % CYCLE.length;
          el('first').src = CYCLE[shown];
        }, FRAME_MS);
      }
    } else if (state.view === 'anaglyph') {
      show(IMAGES.anaglyph);
    } else if (state.view === 'cross') {
      show(IMAGES.right, IMAGES.left);
    } else {
      show(IMAGES.left, IMAGES.right);
    }
  }
  el('before').src = IMAGES.mixture;
  el('after').src = IMAGES.left;
  el('disparity').src = IMAGES.disparity;
  el('slider').addEventListener('input', function () {
    state.slider = Number(el('slider').value);
    drawSlider();
  });
  var buttons = document.querySelectorAll('button[data-view]');
  for (var i = 0; i < buttons.length; i++) {
    buttons[i].addEventListener('click', function (event) {
      state.view = event.target.getAttribute('data-view');
      state.wiggle = false;
      drawPair();
    });
  }
  el('wiggle').addEventListener('change', function () {
    state.wiggle = el('wiggle').checked;
    state.frame = -1;
    drawPair();
  });
  window.addEventListener('hashchange', function () { readHash(); drawSlider(); drawPair(); });
  readHash();
  drawSlider();
  drawPair();
})();
</script>
</body></html>
''')


def data_uri(image: np.ndarray, icc_profile: Optional[bytes] = None) -> str:
  """A uint8 RGB image [H, W, 3] as a base64 JPEG data URI, with `icc_profile` embedded
  when given."""
  buffer = io.BytesIO()
  Image.fromarray(np.ascontiguousarray(image, np.uint8), 'RGB').save(
      buffer, 'JPEG', quality=EMBED_QUALITY, icc_profile=icc_profile)
  return 'data:image/jpeg;base64,' + base64.b64encode(buffer.getvalue()).decode('ascii')


def render(title: str, left: np.ndarray, right: np.ndarray, mixture: np.ndarray,
           disparity: np.ndarray, anaglyph: np.ndarray, between: Sequence[np.ndarray],
           frame_ms: int, icc_profile: Optional[bytes] = None) -> str:
  """The page's HTML text.

  Args:
    title: shown as the heading (HTML-escaped).
    left, right, mixture, disparity, anaglyph: uint8 RGB [H, W, 3]: the views, the input,
      the colour-mapped disparity and the views re-encoded as an anaglyph.
    between: the wiggle's synthesised views from left to right, uint8 RGB [H, W, 3] each.
    frame_ms: milliseconds each wiggle frame is shown.
    icc_profile: the input's colour profile, embedded in every image but the disparity's.
  """
  images = {key: data_uri(image, None if key == 'disparity' else icc_profile)
            for key, image in (('left', left), ('right', right), ('mixture', mixture),
                               ('disparity', disparity), ('anaglyph', anaglyph))}
  return _PAGE.substitute(
      title=html.escape(title), images=json.dumps(images),
      between=json.dumps([data_uri(image, icc_profile) for image in between]),
      frame_ms=int(frame_ms))
