from setuptools import find_packages, setup

package_name = 'emff_studies'

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
    description='EMFF mission studies (seed 004): a mission package spanning the formation laws and the airtrack plant.',
    license='Apache-2.0',
    entry_points={
        'acds.verbs': [f'emff = {package_name}.emff_cli'],
    },
)
