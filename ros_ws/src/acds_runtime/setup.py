from setuptools import find_packages, setup

package_name = 'acds_runtime'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['fastdds_profile.xml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=False,
    maintainer='ACDS emulator team',
    maintainer_email='acds@example.org',
    description='The ACDS runtime: launcher, run monitor and recorder, direct engine, run summaries.',
    license='Apache-2.0',
    # The launch_graph harness as a pytest plugin (issue 20 §5): a user's package tests its node with it.
    entry_points={'pytest11': ['acds = acds_runtime.testing']},
)
