from setuptools import find_packages, setup

package_name = 'canopen_bus'

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
    description='CANopen devices from an object dictionary on a socketcand-protocol bus (spec §13).',
    license='Apache-2.0',
    entry_points={
        'acds.nodes': [f'{package_name} = {package_name}.nodes:PACKAGE'],
        'acds.run_options': [f'{package_name} = {package_name}.run_plugin'],
        'acds.summaries': [f'{package_name} = {package_name}.summary'],
        'acds.contract': [f'{package_name} = {package_name}.contract'],
        'console_scripts': [
            'canopen_cards = canopen_bus.cards_node:main',
            'canopen_bus_hub = canopen_bus.hub:main',
        ],
    },
)
