from setuptools import find_packages, setup

package_name = 'acds_cli'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    # The shipped scenarios (acds_cli/scenarios links to the checkout's scenarios/ folder, where users read
    # and copy them): package data, found through the acds.scenarios entry point below.
    package_data={package_name: ['scenarios/*.yaml', 'scenarios/*.json', 'scenarios/*/*.yaml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=False,
    maintainer='ACDS emulator team',
    maintainer_email='acds@example.org',
    description='The acds command line: run, sweep, Monte Carlo, bags, plots and the design tools.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': ['acds = acds_cli.__main__:main'],
        'acds.scenarios': ['shipped = acds_cli'],
    },
)
