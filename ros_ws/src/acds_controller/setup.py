from setuptools import find_packages, setup

package_name = 'acds_controller'

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
    description='Transfer assembly and DPA control laws: B-dot, B×H, wheel laws (spec §7).',
    license='Apache-2.0',
    entry_points={
        'acds.nodes': [f'{package_name} = {package_name}.nodes:PACKAGE'],
        'acds.summaries': ['aap = acds_controller.aap_summary', 'emff = acds_controller.emff_summary'],
        'acds.plots': ['formation = acds_controller.emff_plots'],
        'console_scripts': [
            'acds_controller = acds_controller.controller_node:main',
            'formation_controller = acds_controller.formation_controller_node:main',
        ],
    },
)
