from setuptools import find_packages, setup

package_name = 'ascs_mode_manager'

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
    description='Mode manager: HEAO Mode 1A→1B→cruise and SSS perigee automatic turn-on (spec §8).',
    license='Apache-2.0',
    entry_points={
        'acds.nodes': [f'{package_name} = {package_name}.nodes:PACKAGE'],
        'acds.summaries': ['sss = ascs_mode_manager.sss_summary'],
        'acds.plots': ['sss = ascs_mode_manager.sss_plots'],
        'console_scripts': [
            'ascs_mode_manager = ascs_mode_manager.mode_manager_node:main'
        ],
    },
)
