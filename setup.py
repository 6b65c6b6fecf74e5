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
    install_requires=[
        'tensorflow>=2.15,<3',
        'numpy>=1.23',
        'opencv-python-headless>=4.6',
        'scikit-image>=0.21',
        'absl-py>=1.0',
        # tf.summary's writers live in tensorboard, which recent TF no longer pulls in.
        'tensorboard>=2.15',
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
