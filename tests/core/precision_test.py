"""Tests of mixstereo_tf.core.precision: the bfloat16 decision from the CPU's flags and its
override."""

import pytest

from mixstereo_tf.core import precision


def _cpuinfo(tmp_path, flags):
  path = tmp_path / 'cpuinfo'
  path.write_text(f'processor\t: 0\nmodel name\t: x\nflags\t\t: fpu sse2 {flags}\n\n'
                  'processor\t: 1\nflags\t\t: fpu avx512_bf16\n')
  return str(path)


@pytest.mark.parametrize('flags, expected', [('avx2 avx512f avx512_bf16', True),
                                             ('amx_tile amx_bf16', True),
                                             ('avx2 avx512f avx512_vnni', False)])
def test_the_first_cpus_flags_decide(tmp_path, monkeypatch, flags, expected):
  monkeypatch.delenv(precision.ENVIRONMENT, raising=False)
  assert precision.inference_bfloat16(_cpuinfo(tmp_path, flags)) is expected


def test_no_cpuinfo_means_float32(tmp_path, monkeypatch):
  monkeypatch.delenv(precision.ENVIRONMENT, raising=False)
  assert precision.inference_bfloat16(str(tmp_path / 'missing')) is False


def test_the_environment_overrides_the_flags_and_a_bad_value_is_named(tmp_path, monkeypatch):
  with_bf16 = _cpuinfo(tmp_path, 'avx512_bf16')
  monkeypatch.setenv(precision.ENVIRONMENT, '0')
  assert precision.inference_bfloat16(with_bf16) is False
  monkeypatch.setenv(precision.ENVIRONMENT, '1')
  assert precision.inference_bfloat16(str(tmp_path / 'missing')) is True
  monkeypatch.setenv(precision.ENVIRONMENT, 'yes')
  with pytest.raises(ValueError, match='MIXSTEREO_BFLOAT16'):
    precision.inference_bfloat16(with_bf16)


def test_an_empty_setting_is_read_as_unset(tmp_path, monkeypatch):
  for value in ('', ' '):
    monkeypatch.setenv(precision.ENVIRONMENT, value)
    assert precision.inference_bfloat16(_cpuinfo(tmp_path, 'avx512_bf16')) is True
    assert precision.inference_bfloat16(_cpuinfo(tmp_path, 'avx2')) is False
