"""results with their uncertainty: u, U and the ISO 14253-1 decision per callout and per gage

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-26 01:15:00

``inspect batch --uncertainty`` and ``gage batch --uncertainty`` store each callout's
(each gage's allowance after T*) standard uncertainty ``u``, expanded uncertainty ``U``
(95 %, JCGM 101), the ISO 14253-1 ``decision`` and the decision rule applied. NULL where a
result was computed without an uncertainty (every row stored before this revision); SPC
then takes the measurement's u from ``--measurement-uncertainty`` only.
"""
from alembic import op
import sqlalchemy as sa


revision = '0004'
down_revision = '0003'
branch_labels = None
depends_on = None


def upgrade() -> None:
    for table in ('inspection_results', 'gage_allowances'):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.add_column(sa.Column('u', sa.Float(), nullable=True))
            batch_op.add_column(sa.Column('expanded_u', sa.Float(), nullable=True))
            batch_op.add_column(sa.Column('decision', sa.String(length=16), nullable=True))
            batch_op.add_column(sa.Column('decision_rule', sa.String(length=64), nullable=True))


def downgrade() -> None:
    for table in ('inspection_results', 'gage_allowances'):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.drop_column('decision_rule')
            batch_op.drop_column('decision')
            batch_op.drop_column('expanded_u')
            batch_op.drop_column('u')
