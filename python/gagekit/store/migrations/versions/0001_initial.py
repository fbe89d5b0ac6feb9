"""initial schema: parts, specs, scans, results, gage/form/inspection results, machines, calibrations, tracking cycles

Revision ID: 0001
Revises: 
Create Date: 2026-11-24 03:24:46.856889
"""
from alembic import op
import sqlalchemy as sa


revision = '0001'
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table('machines',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('name', sa.String(length=200), nullable=False),
    sa.Column('signature', sa.Text(), nullable=False),
    sa.Column('created', sa.DateTime(timezone=True), nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_machines')),
    sa.UniqueConstraint('name', 'signature', name='uq_machines_name_signature')
    )
    op.create_table('parts',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('name', sa.String(length=200), nullable=False),
    sa.Column('created', sa.DateTime(timezone=True), nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_parts')),
    sa.UniqueConstraint('name', name=op.f('uq_parts_name'))
    )
    op.create_table('scans',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('content_hash', sa.String(length=64), nullable=False),
    sa.Column('size_bytes', sa.BigInteger(), nullable=False),
    sa.Column('scanned', sa.DateTime(timezone=True), nullable=False),
    sa.Column('created', sa.DateTime(timezone=True), nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_scans')),
    sa.UniqueConstraint('content_hash', name=op.f('uq_scans_content_hash'))
    )
    op.create_table('calibrations',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('machine_id', sa.Integer(), nullable=False),
    sa.Column('kind', sa.String(length=16), nullable=False),
    sa.Column('created', sa.DateTime(timezone=True), nullable=False),
    sa.Column('source', sa.Text(), nullable=True),
    sa.Column('n_points', sa.Integer(), nullable=False),
    sa.Column('frame', sa.JSON(), nullable=True),
    sa.ForeignKeyConstraint(['machine_id'], ['machines.id'], name=op.f('fk_calibrations_machine_id_machines')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_calibrations'))
    )
    op.create_table('scan_paths',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('scan_id', sa.Integer(), nullable=False),
    sa.Column('path', sa.Text(), nullable=False),
    sa.Column('seen', sa.DateTime(timezone=True), nullable=False),
    sa.ForeignKeyConstraint(['scan_id'], ['scans.id'], name=op.f('fk_scan_paths_scan_id_scans')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_scan_paths')),
    sa.UniqueConstraint('scan_id', 'path', name='uq_scan_paths_scan_id_path')
    )
    op.create_table('specs',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('hash', sa.String(length=64), nullable=False),
    sa.Column('kind', sa.String(length=16), nullable=False),
    sa.Column('part_id', sa.Integer(), nullable=True),
    sa.Column('source', sa.Text(), nullable=True),
    sa.Column('document', sa.JSON(), nullable=False),
    sa.Column('created', sa.DateTime(timezone=True), nullable=False),
    sa.ForeignKeyConstraint(['part_id'], ['parts.id'], name=op.f('fk_specs_part_id_parts')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_specs')),
    sa.UniqueConstraint('hash', name=op.f('uq_specs_hash'))
    )
    op.create_table('cycle_observations',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('calibration_id', sa.Integer(), nullable=False),
    sa.Column('cycle', sa.Integer(), nullable=False),
    sa.Column('idx', sa.Integer(), nullable=False),
    sa.Column('commands', sa.JSON(), nullable=False),
    sa.Column('x', sa.Float(), nullable=False),
    sa.Column('y', sa.Float(), nullable=False),
    sa.Column('z', sa.Float(), nullable=False),
    sa.ForeignKeyConstraint(['calibration_id'], ['calibrations.id'], name=op.f('fk_cycle_observations_calibration_id_calibrations')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_cycle_observations'))
    )
    op.create_table('cycle_residuals',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('calibration_id', sa.Integer(), nullable=False),
    sa.Column('cycle', sa.Integer(), nullable=False),
    sa.Column('idx', sa.Integer(), nullable=False),
    sa.Column('full', sa.Float(), nullable=False),
    sa.Column('static', sa.Float(), nullable=False),
    sa.Column('drift_only', sa.Float(), nullable=False),
    sa.ForeignKeyConstraint(['calibration_id'], ['calibrations.id'], name=op.f('fk_cycle_residuals_calibration_id_calibrations')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_cycle_residuals'))
    )
    op.create_table('cycle_temperatures',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('calibration_id', sa.Integer(), nullable=False),
    sa.Column('cycle', sa.Integer(), nullable=False),
    sa.Column('sensor', sa.String(length=64), nullable=False),
    sa.Column('value', sa.Float(), nullable=False),
    sa.ForeignKeyConstraint(['calibration_id'], ['calibrations.id'], name=op.f('fk_cycle_temperatures_calibration_id_calibrations')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_cycle_temperatures'))
    )
    op.create_table('group_values',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('calibration_id', sa.Integer(), nullable=False),
    sa.Column('cycle', sa.Integer(), nullable=False),
    sa.Column('name', sa.Text(), nullable=False),
    sa.Column('value', sa.Float(), nullable=False),
    sa.Column('unit', sa.String(length=32), nullable=True),
    sa.Column('effect_mm', sa.Float(), nullable=True),
    sa.ForeignKeyConstraint(['calibration_id'], ['calibrations.id'], name=op.f('fk_group_values_calibration_id_calibrations')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_group_values'))
    )
    op.create_table('results',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('scan_id', sa.Integer(), nullable=False),
    sa.Column('spec_id', sa.Integer(), nullable=False),
    sa.Column('path', sa.Text(), nullable=False),
    sa.Column('status', sa.String(length=8), nullable=False),
    sa.Column('error', sa.Text(), nullable=True),
    sa.Column('result', sa.JSON(), nullable=True),
    sa.Column('started', sa.DateTime(timezone=True), nullable=False),
    sa.Column('finished', sa.DateTime(timezone=True), nullable=False),
    sa.Column('seconds', sa.Float(), nullable=False),
    sa.Column('worker', sa.String(length=200), nullable=True),
    sa.ForeignKeyConstraint(['scan_id'], ['scans.id'], name=op.f('fk_results_scan_id_scans')),
    sa.ForeignKeyConstraint(['spec_id'], ['specs.id'], name=op.f('fk_results_spec_id_specs')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_results')),
    sa.UniqueConstraint('scan_id', 'spec_id', name='uq_results_scan_id_spec_id')
    )
    with op.batch_alter_table('results', schema=None) as batch_op:
        batch_op.create_index('ix_results_spec_id_finished', ['spec_id', 'finished'], unique=False)

    op.create_table('tracking_cycles',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('calibration_id', sa.Integer(), nullable=False),
    sa.Column('cycle', sa.Integer(), nullable=False),
    sa.Column('time', sa.Float(), nullable=True),
    sa.Column('stats', sa.JSON(), nullable=False),
    sa.ForeignKeyConstraint(['calibration_id'], ['calibrations.id'], name=op.f('fk_tracking_cycles_calibration_id_calibrations')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_tracking_cycles')),
    sa.UniqueConstraint('calibration_id', 'cycle', name='uq_tracking_cycles_calibration_id_cycle')
    )
    op.create_table('form_results',
    sa.Column('result_id', sa.Integer(), nullable=False),
    sa.Column('shape', sa.String(length=32), nullable=False),
    sa.Column('criterion', sa.String(length=32), nullable=False),
    sa.Column('n_points', sa.Integer(), nullable=False),
    sa.Column('form_error', sa.Float(), nullable=False),
    sa.Column('radius', sa.Float(), nullable=True),
    sa.ForeignKeyConstraint(['result_id'], ['results.id'], name=op.f('fk_form_results_result_id_results')),
    sa.PrimaryKeyConstraint('result_id', name=op.f('pk_form_results'))
    )
    op.create_table('gage_allowances',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('result_id', sa.Integer(), nullable=False),
    sa.Column('gage', sa.String(length=200), nullable=False),
    sa.Column('region', sa.String(length=200), nullable=False),
    sa.Column('points', sa.Integer(), nullable=False),
    sa.Column('filtered_points', sa.Integer(), nullable=False),
    sa.Column('allowance_before', sa.Float(), nullable=False),
    sa.Column('allowance_after', sa.Float(), nullable=False),
    sa.Column('q', sa.Float(), nullable=False),
    sa.Column('slack', sa.Float(), nullable=False),
    sa.ForeignKeyConstraint(['result_id'], ['results.id'], name=op.f('fk_gage_allowances_result_id_results')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_gage_allowances')),
    sa.UniqueConstraint('result_id', 'gage', name='uq_gage_allowances_result_id_gage')
    )
    op.create_table('gage_checks',
    sa.Column('result_id', sa.Integer(), nullable=False),
    sa.Column('status', sa.String(length=16), nullable=False),
    sa.Column('objective', sa.Float(), nullable=False),
    sa.Column('largest_release', sa.Float(), nullable=False),
    sa.Column('alpha', sa.Float(), nullable=False),
    sa.Column('beta', sa.Float(), nullable=False),
    sa.Column('gamma', sa.Float(), nullable=False),
    sa.Column('dx', sa.Float(), nullable=False),
    sa.Column('dy', sa.Float(), nullable=False),
    sa.Column('dz', sa.Float(), nullable=False),
    sa.ForeignKeyConstraint(['result_id'], ['results.id'], name=op.f('fk_gage_checks_result_id_results')),
    sa.PrimaryKeyConstraint('result_id', name=op.f('pk_gage_checks'))
    )
    op.create_table('inspection_results',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('result_id', sa.Integer(), nullable=False),
    sa.Column('tolerance', sa.String(length=200), nullable=False),
    sa.Column('characteristic', sa.String(length=64), nullable=False),
    sa.Column('value', sa.Float(), nullable=False),
    sa.Column('lower', sa.Float(), nullable=True),
    sa.Column('upper', sa.Float(), nullable=True),
    sa.Column('conforming', sa.Boolean(), nullable=False),
    sa.ForeignKeyConstraint(['result_id'], ['results.id'], name=op.f('fk_inspection_results_result_id_results')),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_inspection_results')),
    sa.UniqueConstraint('result_id', 'tolerance', name='uq_inspection_results_result_id_tolerance')
    )


def downgrade() -> None:
    op.drop_table('inspection_results')
    op.drop_table('gage_checks')
    op.drop_table('gage_allowances')
    op.drop_table('form_results')
    op.drop_table('tracking_cycles')
    with op.batch_alter_table('results', schema=None) as batch_op:
        batch_op.drop_index('ix_results_spec_id_finished')

    op.drop_table('results')
    op.drop_table('group_values')
    op.drop_table('cycle_temperatures')
    op.drop_table('cycle_residuals')
    op.drop_table('cycle_observations')
    op.drop_table('specs')
    op.drop_table('scan_paths')
    op.drop_table('calibrations')
    op.drop_table('scans')
    op.drop_table('parts')
    op.drop_table('machines')
