from setuptools import find_packages, setup

package_name = 'aap_mission'

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
    description='AAP Workshop CMG dump mission (seed 000): the dump report and studies, and the dump magnet sizing.',
    license='Apache-2.0',
    entry_points={
        'acds.verbs': ['aap = aap_mission.dump_report_cli',
                       'size_magnet = aap_mission.magnet_sizing_cli'],
    },
)
