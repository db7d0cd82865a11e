from setuptools import find_packages, setup

package_name = 'oresat_mission'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ACDS emulator team',
    maintainer_email='acds@example.org',
    description='OreSat mission (seed 003): the torque-rod design verb.',
    license='Apache-2.0',
    entry_points={
        'acds.verbs': ['oresat = oresat_mission.torque_rod_cli'],
    },
)
