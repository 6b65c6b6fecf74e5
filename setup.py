"""Install script for mixstereo_tf."""

import setuptools

setuptools.setup(
    name='mixstereo_tf',
    version='0.1.0',
    description=('TensorFlow 2 reimplementation of "Stereo Computation for a Single '
                 'Mixture Image" (Zhong, Dai, Li, ECCV 2018).'),
    long_description=open('README.md', encoding='utf-8').read(),
    long_description_content_type='text/markdown',
    license='Apache-2.0',
    python_requires='>=3.9',
    # The repository's top-level data_lists/ (the KITTI split lists) is installed as package
    # data mixstereo_tf/data_lists/, where mixstereo_tf.data.split_lists finds it.
    # Folders of data only (data_lists/kitti, a shipped model's folder) are listed as
    # namespace packages: setuptools warned about each (10 warnings, 40 lines apiece, on
    # every install) and will stop installing their files otherwise.
    packages=setuptools.find_namespace_packages(
        include=['mixstereo_tf', 'mixstereo_tf.*'], exclude=['*.__pycache__']) + [
            'mixstereo_tf.data_lists'] + [
                f'mixstereo_tf.data_lists.{name}'
                for name in setuptools.find_namespace_packages(where='data_lists')],
    package_dir={'mixstereo_tf.data_lists': 'data_lists'},
    # The shipped models (mixstereo_tf/artifacts/pretrained/NAME/{info.json,weights.npz}).
    package_data={'mixstereo_tf.data_lists': ['README.md', 'kitti/*.txt', 'middlebury/*.txt',
                                              'photos/*.txt'],
                  'mixstereo_tf.artifacts.pretrained': ['*/info.json', '*/weights.npz']},
    include_package_data=True,
    # classical/sgm.py uses np.bitwise_count (numpy >= 2.0). The TF, OpenCV, scikit-image and
    # SciPy bounds are their first releases built for numpy 2; older wheels need numpy < 2.
    install_requires=[
        'tensorflow>=2.18,<3',
        'numpy>=2.0',
        'opencv-python-headless>=4.10',
        'scikit-image>=0.24',
        # cli/stereo_formats.py: MPO (CIPA DC-007), JPS and the wiggle GIF. scikit-image
        # pulls it in already; named because without it the MPO's APP2 MP index (entry
        # offsets patched after both JPEGs are written) is written by hand. MPO saving: 9.3.
        'Pillow>=9.3',
        # data/image_io.py: HEIC / HEIF, phones' default photo format, through Pillow. No
        # other decoder at hand does it whole: OpenCV and Pillow read none, PyAV decodes the
        # HEVC image at its coded size (80x64 for an 80x48 photo) without the file's
        # rotation, mirror or EXIF. 5.7 MB wheel (libheif, libde265, x265), 25 ms to import.
        'pillow-heif>=0.18',
        # classical/diplopia.py solves its layer system with scipy.sparse.
        'scipy>=1.13',
        # classical/matcher.py's census-SGM kernels. Against the NumPy classical/sgm.py on
        # one red-cyan anaglyph, 2 cores (experiments/benchmark.py --sections=matcher; CPU-s,
        # peak memory above the process' resident memory before the call): 1242x375 [0, 127] 0.48 vs 3.64 CPU-s, 0.14 vs
        # 0.50 GiB; 1280x720 [-58, 58] 1.08 vs 7.05 CPU-s (0.41 with a video prior), 0.30
        # vs 0.91 GiB; 4000x3000 [-181, 181] 15.6 CPU-s, 1.2 GiB, where NumPy's cost volumes
        # alone would take 17 GB. Compiled once (~10 CPU-s), then loaded from numba's disk
        # cache (~0.5 CPU-s per process).
        'numba>=0.60',
        # mixstereo_tf/video/streams.py: FFmpeg's libraries in-process (PyAV >= 14 for
        # add_stream_from_template; the wheels bundle FFmpeg with libx264).
        'av>=14',
        'absl-py>=1.0',
        # tf.summary's writers live in tensorboard, which recent TF no longer pulls in.
        'tensorboard>=2.18',
    ],
    extras_require={
        # imageio-ffmpeg ships a static FFmpeg binary (with the stereo3d filter): the
        # independent anaglyph encoder of tests/unmixing/detection_test.py and the real-world
        # evaluation (evaluation/ffmpeg_encoder.py). PyAV's wheels lack stereo3d.
        # apache-beam (tests/cli/beam_batch_test.py runs the batch pipeline) as in 'beam'.
        # pytest-xdist runs the suite in one process per core (README's command, -n auto,
        # at most 4): on 2 cores 829 tests took 571 s in 2 processes against 1064-1138 s
        # in one (2026-11-26), under the ~15 minutes the suite is kept to.
        'test': ['pytest>=7', 'pytest-xdist>=3', 'imageio-ffmpeg>=0.5', 'apache-beam>=2.61'],
        'eval': ['imageio-ffmpeg>=0.5'],
        # mixstereo-batch (cli/beam_batch.py, the one module importing Beam): an extra, not a
        # base requirement, since apache-beam 2.77 adds 315 MB to site-packages (pyarrow 156
        # MB, apache_beam 100 MB; 14 packages), takes 0.8-1.9 s to import and downgrades
        # protobuf 7 -> 6 and pillow 13 -> 12 (TF 2.21 takes protobuf >= 6.31.1; the cli and
        # unmix tests pass with both). >= 2.61: the first to accept NumPy 2 (tested: 2.77).
        'beam': ['apache-beam>=2.61'],
        # A GPU: TensorFlow with its CUDA and cuDNN wheels (`tensorflow` alone finds no GPU
        # and trains on the CPU; every binary's first log line says which).
        'gpu': ['tensorflow[and-cuda]>=2.18,<3'],
    },
    entry_points={
        'console_scripts': [
            'mixstereo-train=mixstereo_tf.train:run',
            'mixstereo-eval=mixstereo_tf.evaluate:run',
            'mixstereo-export=mixstereo_tf.export:run',
            'mixstereo-unmix=mixstereo_tf.unmix:run',
            'mixstereo-batch=mixstereo_tf.batch:run',
        ],
    },
    classifiers=[
        'Programming Language :: Python :: 3',
        'Topic :: Scientific/Engineering :: Image Recognition',
    ],
)
