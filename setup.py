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
    packages=setuptools.find_packages(include=['mixstereo_tf', 'mixstereo_tf.*']),
    include_package_data=True,
    # baselines/sgm.py uses np.bitwise_count (numpy >= 2.0). The TF, OpenCV, scikit-image and
    # SciPy bounds are their first releases built for numpy 2; older wheels need numpy < 2.
    install_requires=[
        'tensorflow>=2.18,<3',
        'numpy>=2.0',
        'opencv-python-headless>=4.10',
        'scikit-image>=0.24',
        # baselines/diplopia.py solves its layer system with scipy.sparse.
        'scipy>=1.13',
        'absl-py>=1.0',
        # tf.summary's writers live in tensorboard, which recent TF no longer pulls in.
        'tensorboard>=2.18',
    ],
    extras_require={'test': ['pytest>=7']},
    entry_points={
        'console_scripts': [
            'mixstereo-train=mixstereo_tf.train:run',
            'mixstereo-eval=mixstereo_tf.evaluate:run',
            'mixstereo-export=mixstereo_tf.export:run',
            'mixstereo-unmix=mixstereo_tf.unmix:run',
        ],
    },
    classifiers=[
        'Programming Language :: Python :: 3',
        'Topic :: Scientific/Engineering :: Image Recognition',
    ],
)
