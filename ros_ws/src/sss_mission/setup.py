from setuptools import find_packages, setup

package_name = 'sss_mission'

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
    description='SSS mission (seed 001): the spin-mode mechanizations and the torque-meter test verbs.',
    license='Apache-2.0',
    entry_points={
        'acds.verbs': ['mechanizations = sss_mission.mechanizations_cli',
                       'torque_meter = sss_mission.torque_meter_cli'],
    },
)
