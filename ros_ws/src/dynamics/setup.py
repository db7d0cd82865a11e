from setuptools import find_packages, setup

package_name = 'dynamics'

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
    description='Rigid-body dynamics, environment (orbit, tilted-dipole field, sun) and reaction wheels (spec §3, §4).',
    license='Apache-2.0',
    entry_points={
        'acds.nodes': [f'{package_name} = {package_name}.nodes:PACKAGE'],
        'console_scripts': [
            'rigid_body = dynamics.rigid_body_node:main',
            'reaction_wheels = dynamics.reaction_wheels_node:main',
            'formation_dynamics = dynamics.formation_node:main',
        ],
    },
)
