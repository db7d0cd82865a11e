from setuptools import find_packages, setup

package_name = 'em_driver'

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
    description='Electromagnets and bridge-switch drivers with the ±ε hysteresis current band (spec §6).',
    license='Apache-2.0',
    entry_points={
        'acds.nodes': [f'{package_name} = {package_name}.nodes:PACKAGE'],
        'acds.summaries': ['oresat = em_driver.oresat_summary'],
        'acds.plots': ['torque_rod = em_driver.oresat_plots'],
        'console_scripts': [
            'em_driver = em_driver.em_driver_node:main'
        ],
    },
)
