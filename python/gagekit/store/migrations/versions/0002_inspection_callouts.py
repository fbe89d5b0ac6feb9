"""inspection callouts: feature, datum reference frame, zone kind and point count

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-24 06:55:00

The ``inspection_results`` rows of revision 0001 held a callout's name, characteristic,
value and limits only; SPC per feature or per datum frame needs what the callout is.
The new columns are filled for the rows already stored from their results' JSON (what
``gagekit inspect --json`` printed), matched by the same callout names.
"""
from alembic import op
import sqlalchemy as sa


revision = '0002'
down_revision = '0001'
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table('inspection_results', schema=None) as batch_op:
        batch_op.add_column(sa.Column('feature', sa.String(length=200), nullable=True))
        batch_op.add_column(sa.Column('datums', sa.String(length=64), nullable=True))
        batch_op.add_column(sa.Column('zone', sa.String(length=32), nullable=True))
        batch_op.add_column(sa.Column('n_points', sa.Integer(), nullable=True))
    _backfill(op.get_bind())


def downgrade() -> None:
    with op.batch_alter_table('inspection_results', schema=None) as batch_op:
        batch_op.drop_column('n_points')
        batch_op.drop_column('zone')
        batch_op.drop_column('datums')
        batch_op.drop_column('feature')


def _numbered(names: list) -> list:
    out, seen = [], set()
    for name in names:
        base, k = name, 2
        while name in seen:
            name, k = f"{base} #{k}", k + 1
        seen.add(name)
        out.append(name)
    return out


def _names(result) -> list:
    """(name in revision 0001, name from revision 0002, callout) of a result's callouts.
    0001 named a callout by its name, else "characteristic of feature"; 0002 adds the
    datum frame, "characteristic of feature |A|B|"; repeated names are numbered "#2"..."""
    tols = [t for t in result.get("tolerances", []) if isinstance(t, dict)]
    old = _numbered([t.get("name") or f"{t['characteristic']} of {t['feature']}" for t in tols])
    new = _numbered([t.get("name") or (f"{t['characteristic']} of {t['feature']}"
                                       + (f" |{'|'.join(t['datums'])}|" if t.get("datums") else "")) for t in tols])
    return list(zip(old, new, tols))


def _backfill(conn) -> None:
    """Fill the new columns of the stored callouts from their results' JSON and give them
    the names of revision 0002 (through temporary names: (result, name) is unique)."""
    meta = sa.MetaData()
    results = sa.Table('results', meta, sa.Column('id', sa.Integer), sa.Column('result', sa.JSON))
    rows = sa.Table('inspection_results', meta, sa.Column('result_id', sa.Integer), sa.Column('tolerance', sa.String),
                    sa.Column('feature', sa.String), sa.Column('datums', sa.String), sa.Column('zone', sa.String),
                    sa.Column('n_points', sa.Integer))
    ids = sa.select(rows.c.result_id).distinct()
    rename = (rows.update().where(rows.c.result_id == sa.bindparam('rid'), rows.c.tolerance == sa.bindparam('old'))
              .values(tolerance=sa.bindparam('new')))
    fill = (rows.update().where(rows.c.result_id == sa.bindparam('rid'), rows.c.tolerance == sa.bindparam('tmp'))
            .values(tolerance=sa.bindparam('new'), feature=sa.bindparam('f'), datums=sa.bindparam('d'),
                    zone=sa.bindparam('z'), n_points=sa.bindparam('n')))
    for rid, result in conn.execute(sa.select(results.c.id, results.c.result).where(results.c.id.in_(ids))).all():
        if not isinstance(result, dict):
            continue
        names = _names(result)
        if not names:
            continue
        conn.execute(rename, [{'rid': rid, 'old': old, 'new': f'\x01{k}'} for k, (old, _, _) in enumerate(names)])
        conn.execute(fill, [{'rid': rid, 'tmp': f'\x01{k}', 'new': new, 'f': t.get('feature'),
                             'd': '|'.join(t.get('datums') or []), 'z': t.get('zone'), 'n': t.get('n_points')}
                            for k, (_, new, t) in enumerate(names)])
