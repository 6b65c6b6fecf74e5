"""The numba kernels of `diplopia_layers.separate_layers`: its normal equations applied
without a sparse matrix, and the conjugate-gradient updates, row block by row block.

The unknown left layer u lives on [H, E] pixels (E = W + extra columns), 3 channels. Row y
of the data operator D maps u to [H, W] values

    (D u)(y, x) = a u(y, x) + (1 - a) ((1 - f) u(y, x0) + f u(y, x0 + 1)),

x0 + f = clip(x + d_R(y, x), 0, E - 1.001) (x0 integer, f its fraction); the normal
matrix is A = D^T D + s G^T G + c I with G the horizontal and vertical first differences
of the [H, E] grid (s: smoothness, c: fidelity). D couples pixels of one row only and G
rows y - 1 and y + 1, so rows [y0, y1) of A u read u's rows [y0 - 1, y1] and write only
their own: row blocks run in Python threads (the kernels release the GIL). float64.
"""

import numba


@numba.njit(nogil=True, cache=True, error_model='numpy')
def diagonal_rows(y0, y1, x0, frac, weight, smoothness, fidelity, out):
  """out[y, :] = diag(A) for rows [y0, y1) (float64 [H, E]; x0 int64 and frac float64
  [H, W]); the coefficients of one output pixel that fall on one column are summed
  first, as a sparse matrix built from them sums duplicates."""
  height, wide = out.shape
  other = 1.0 - weight
  for y in range(y0, y1):
    vertical = int(y > 0) + int(y < height - 1)
    for column in range(wide):
      out[y, column] = fidelity + smoothness * (vertical + int(column > 0) +
                                                int(column < wide - 1))
    for x in range(x0.shape[1]):
      columns = (x, x0[y, x], x0[y, x] + 1)
      values = (weight, other * (1.0 - frac[y, x]), other * frac[y, x])
      for k in range(3):
        total = 0.0
        first = True
        for j in range(3):
          if columns[j] == columns[k]:
            if j < k:
              first = False
            total += values[j]
        if first:
          out[y, columns[k]] += total * total


@numba.njit(nogil=True, cache=True, error_model='numpy')
def transpose_rows(y0, y1, values, x0, frac, weight, out):
  """out[y] = (D^T values)[y] for rows [y0, y1) (values [H, W, C], out [H, E, C])."""
  other = 1.0 - weight
  for y in range(y0, y1):
    out[y] = 0.0
    for x in range(values.shape[1]):
      left, right = other * (1.0 - frac[y, x]), other * frac[y, x]
      for c in range(values.shape[2]):
        value = values[y, x, c]
        out[y, x, c] += weight * value
        out[y, x0[y, x], c] += left * value
        out[y, x0[y, x] + 1, c] += right * value


@numba.njit(nogil=True, cache=True, error_model='numpy')
def normal_rows(y0, y1, u, x0, frac, weight, smoothness, fidelity, out, dots):
  """out[y] = (A u)[y] for rows [y0, y1) (u, out [H, E, C]); dots[c] += the rows' share
  of <u, A u> per channel."""
  height, wide, channels = u.shape
  other = 1.0 - weight
  for y in range(y0, y1):
    for column in range(wide):
      for c in range(channels):
        value = u[y, column, c]
        total = fidelity * value
        if column > 0:
          total += smoothness * (value - u[y, column - 1, c])
        if column < wide - 1:
          total += smoothness * (value - u[y, column + 1, c])
        if y > 0:
          total += smoothness * (value - u[y - 1, column, c])
        if y < height - 1:
          total += smoothness * (value - u[y + 1, column, c])
        out[y, column, c] = total
    for x in range(x0.shape[1]):
      left, right = other * (1.0 - frac[y, x]), other * frac[y, x]
      a, b = x0[y, x], x0[y, x] + 1
      for c in range(channels):
        data = weight * u[y, x, c] + left * u[y, a, c] + right * u[y, b, c]
        out[y, x, c] += weight * data
        out[y, a, c] += left * data
        out[y, b, c] += right * data
    for column in range(wide):
      for c in range(channels):
        dots[c] += u[y, column, c] * out[y, column, c]


@numba.njit(nogil=True, cache=True, error_model='numpy')
def start_rows(y0, y1, rhs, product, inverse_diagonal, residual, direction, sums):
  """CG's start on rows [y0, y1): residual = rhs - product (product = A u0), direction =
  residual * inverse_diagonal; per channel c, sums[c] += <residual, direction>,
  sums[C + c] += |residual|^2 and sums[2 C + c] += |rhs|^2."""
  channels = rhs.shape[2]
  for y in range(y0, y1):
    for column in range(rhs.shape[1]):
      for c in range(channels):
        target = rhs[y, column, c]
        value = target - product[y, column, c]
        residual[y, column, c] = value
        scaled = value * inverse_diagonal[y, column]
        direction[y, column, c] = scaled
        sums[c] += value * scaled
        sums[channels + c] += value * value
        sums[2 * channels + c] += target * target


@numba.njit(nogil=True, cache=True, error_model='numpy')
def step_rows(y0, y1, alpha, solution, residual, direction, product, inverse_diagonal,
              preconditioned, sums):
  """One CG step on rows [y0, y1): solution += alpha direction, residual -= alpha
  product, preconditioned = residual * inverse_diagonal; per channel c, sums[c] +=
  <residual, preconditioned> and sums[C + c] += |residual|^2 (alpha float64 [C])."""
  channels = solution.shape[2]
  for y in range(y0, y1):
    for column in range(solution.shape[1]):
      for c in range(solution.shape[2]):
        solution[y, column, c] += alpha[c] * direction[y, column, c]
        value = residual[y, column, c] - alpha[c] * product[y, column, c]
        residual[y, column, c] = value
        scaled = value * inverse_diagonal[y, column]
        preconditioned[y, column, c] = scaled
        sums[c] += value * scaled
        sums[channels + c] += value * value


@numba.njit(nogil=True, cache=True, error_model='numpy')
def direction_rows(y0, y1, beta, preconditioned, direction):
  """direction = preconditioned + beta direction on rows [y0, y1) (beta float64 [C])."""
  for y in range(y0, y1):
    for column in range(direction.shape[1]):
      for c in range(direction.shape[2]):
        direction[y, column, c] = (preconditioned[y, column, c] +
                                   beta[c] * direction[y, column, c])


@numba.njit(nogil=True, cache=True, error_model='numpy')
def views_rows(y0, y1, wide, x0, frac, left, right):
  """The views of rows [y0, y1) from the solved left layer `wide` ([H, E, C]), clipped to
  [0, 1]: left[y, x] = wide[y, x] and right[y, x] = (1 - f) wide[y, x0] + f wide[y, x0 + 1]
  (the right pixel shows the left layer at x + d_R; `left`, `right` [H, W, C])."""
  for y in range(y0, y1):
    for x in range(left.shape[1]):
      a, b, f = x0[y, x], x0[y, x] + 1, frac[y, x]
      for c in range(left.shape[2]):
        left[y, x, c] = min(max(wide[y, x, c], 0.0), 1.0)
        value = (1.0 - f) * wide[y, a, c] + f * wide[y, b, c]
        right[y, x, c] = min(max(value, 0.0), 1.0)
