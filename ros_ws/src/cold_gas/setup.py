from setuptools import find_packages, setup

package_name = 'cold_gas'

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
    description='HEAO cold-gas reaction control subsystem: tanks, regulators, pressure switch, six thrusters (seed 002 §5).',
    license='Apache-2.0',
    entry_points={
        'acds.nodes': [f'{package_name} = {package_name}.nodes:PACKAGE'],
        'acds.summaries': ['cold_gas = cold_gas.cold_gas_summary'],
        'acds.plots': ['cold_gas = cold_gas.cold_gas_plots'],
        'console_scripts': [
            'cold_gas = cold_gas.cold_gas_node:main'
        ],
    },
)
