"""Alembic environment of the gagekit results database.

gagekit runs the migrations itself (:func:`gagekit.store.schema.upgrade`), handing Alembic
an open connection in ``config.attributes["connection"]``; the ``alembic`` command line
works too with ``-x url=...``.
"""

from alembic import context
from sqlalchemy import create_engine

from gagekit.store.models import Base

config = context.config
target_metadata = Base.metadata


def _run(connection) -> None:
    context.configure(connection=connection, target_metadata=target_metadata,
                      render_as_batch=connection.dialect.name == "sqlite")
    with context.begin_transaction():
        context.run_migrations()


connection = config.attributes.get("connection")
if connection is not None:
    _run(connection)
else:  # pragma: no cover - the alembic command line
    url = context.get_x_argument(as_dictionary=True).get("url") or config.get_main_option("sqlalchemy.url")
    with create_engine(url).connect() as conn:
        _run(conn)
