from setuptools import find_packages, setup

package_name = 'heao_mission'

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
    description='HEAO acquisition mission (seed 002): a mission package spanning the mode logic and the wheels.',
    license='Apache-2.0',
    entry_points={
        'acds.summaries': [f'heao = {package_name}.heao_summary'],
        'acds.verbs': [f'cold_gas = {package_name}.cold_gas_budget_cli', f'duty_curve = {package_name}.duty_curve_cli',
                       f'explain_sample = {package_name}.explain_cli'],
        'acds.limits': [f'heao = {package_name}.limits'],
        'acds.study_budgets': [f'cold_gas = {package_name}.cold_gas_trade'],
    },
)
