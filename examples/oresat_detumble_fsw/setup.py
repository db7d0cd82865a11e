from setuptools import find_packages, setup

package_name = 'oresat_detumble_fsw'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=False,
    maintainer='ACDS emulator team',
    maintainer_email='acds@example.org',
    description="OreSat B-cross-omega detumble flight software (a user's node for the ACDS emulator)",
    license='Apache-2.0',
    entry_points={
        'console_scripts': [f'{package_name} = {package_name}.detumble_node:main',
                            f'oresat_detumble_canopen = {package_name}.canopen_master:main'],
    },
)
