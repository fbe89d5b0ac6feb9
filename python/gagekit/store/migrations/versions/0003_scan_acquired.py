"""scans: acquisition time from the scan file's own header

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-25 18:30:00

``scans.scanned`` is the file's modification time: copies, downloads and exports rewrite
it (eight files written within milliseconds gave a trend of 792 mm/day). The new column
holds the time the scanner recorded in the file (E57 ``acquisitionStart``, LAS file
creation date), NULL where the format has none; SPC orders and trends results by it,
else by the time the result was stored. Rows stored before this revision keep NULL (the
files may be gone): their results are timed by when they were stored.
"""
from alembic import op
import sqlalchemy as sa


revision = '0003'
down_revision = '0002'
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table('scans', schema=None) as batch_op:
        batch_op.add_column(sa.Column('acquired', sa.DateTime(timezone=True), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table('scans', schema=None) as batch_op:
        batch_op.drop_column('acquired')
