"""The matrix-free normal equations of the layer solve against a sparse matrix built from
`layers_kernel`'s definition, entry by entry."""

import numpy as np
import pytest
import scipy.sparse

from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.classical import layers_kernel


def _sparse_normal(x0, frac, wide, weight, smoothness, fidelity):
  """A = D^T D + s G^T G + c I as a scipy matrix (duplicates summed by scipy)."""
  h, w = x0.shape
  index = np.arange(h * wide).reshape(h, wide)
  rows = np.tile(np.arange(h * w), 3)
  columns = np.concatenate([index[:, :w].ravel(),
                            np.take_along_axis(index, x0, axis=1).ravel(),
                            np.take_along_axis(index, x0 + 1, axis=1).ravel()])
  values = np.concatenate([np.full(h * w, weight), (1 - weight) * (1 - frac.ravel()),
                           (1 - weight) * frac.ravel()])
  data = scipy.sparse.csr_matrix((values, (rows, columns)), shape=(h * w, h * wide))
  diff = lambda n: scipy.sparse.diags([-1.0, 1.0], [0, 1], shape=(n - 1, n))
  grad = scipy.sparse.vstack([scipy.sparse.kron(scipy.sparse.identity(h), diff(wide)),
                              scipy.sparse.kron(diff(h), scipy.sparse.identity(wide))])
  return (data.T @ data + smoothness * grad.T @ grad +
          fidelity * scipy.sparse.identity(h * wide)).tocsr(), data


@pytest.mark.parametrize('weight', [0.5, 0.3])
def test_the_kernels_apply_the_sparse_normal_matrix(weight):
  rng = np.random.default_rng(0)
  h, w, extra = 5, 12, 6
  d_right = rng.uniform(0, 5, (h, w))
  d_right[0, :4] = 0.0  # Lag 0: the own and the shifted tap share a column.
  x0, frac = diplopia_layers._taps(d_right, w + extra)  # pylint: disable=protected-access
  normal, data = _sparse_normal(x0, frac, w + extra, weight, 0.01, 0.05)
  u = rng.normal(size=(h, w + extra, 3))
  out, dots = np.empty_like(u), np.zeros(3)
  layers_kernel.normal_rows(0, h, u, x0, frac, weight, 0.01, 0.05, out, dots)
  want = (normal @ u.reshape(-1, 3)).reshape(u.shape)
  np.testing.assert_allclose(out, want, atol=1e-12)
  np.testing.assert_allclose(dots, np.einsum('ijk,ijk->k', u, want), rtol=1e-12)
  diagonal = np.empty((h, w + extra))
  layers_kernel.diagonal_rows(0, h, x0, frac, weight, 0.01, 0.05, diagonal)
  np.testing.assert_allclose(diagonal.ravel(), normal.diagonal(), atol=1e-12)
  values = rng.normal(size=(h, w, 3))
  transposed = np.empty_like(u)
  layers_kernel.transpose_rows(0, h, values, x0, frac, weight, transposed)
  np.testing.assert_allclose(transposed.reshape(-1, 3), data.T @ values.reshape(-1, 3),
                             atol=1e-12)


def test_the_solve_meets_its_tolerance_in_row_blocks():
  rng = np.random.default_rng(1)
  h, w = 20, 30
  d_right = rng.uniform(1, 6, (h, w))
  mixture = rng.uniform(0, 1, (h, w, 3))
  config = diplopia_layers.LayerConfig(cg_tolerance=1e-8, cg_iterations=2000)
  out = diplopia_layers.separate_layers(mixture, d_right, config, weight=0.4)
  extra = int(np.ceil(d_right.max())) + 2
  x0, frac = diplopia_layers._taps(d_right, w + extra)  # pylint: disable=protected-access
  normal, data = _sparse_normal(x0, frac, w + extra, 0.4, config.smoothness, config.fidelity)
  start = np.pad(mixture, ((0, 0), (0, extra), (0, 0)), mode='edge').reshape(-1, 3)
  exact = scipy.sparse.linalg.spsolve(normal.tocsc(), data.T @ mixture.reshape(-1, 3) +
                                      config.fidelity * start).reshape(h, w + extra, 3)
  np.testing.assert_allclose(out['left'], np.clip(exact[:, :w], 0, 1), atol=1e-5)
