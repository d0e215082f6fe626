-- The PostgreSQL store: the schema of SQLite's migrations 0001–0008 (server/migrations/)
-- in one file. Later migrations go into both folders under the same number (from 0009).
-- Same tables and columns; every integer is BIGINT and every real DOUBLE PRECISION (both
-- decoded as by SQLite: i64, f64), JSON stays TEXT, times are RFC 3339 TEXT written by the
-- server. The history tables have a `rowid` column, named like SQLite's implicit one, so
-- the same `ORDER BY rowid` reads them in insertion order.

-- Jobs, their queue state, and what their runs produced.
CREATE TABLE jobs (
    seq              BIGSERIAL PRIMARY KEY,
    id               TEXT NOT NULL UNIQUE,
    name             TEXT NOT NULL,
    status           TEXT NOT NULL,
    priority         BIGINT NOT NULL DEFAULT 0,
    labels           TEXT NOT NULL DEFAULT '{}',
    scene            TEXT NOT NULL,
    end_time         DOUBLE PRECISION NOT NULL,
    created_at       TEXT NOT NULL,
    started_at       TEXT,
    finished_at      TEXT,
    -- claims that count towards the attempt limit
    attempts         BIGINT NOT NULL DEFAULT 0,
    -- fencing token: +1 on every claim, never decreases
    fence            BIGINT NOT NULL DEFAULT 0,
    worker_id        TEXT,
    lease_until_ms   BIGINT,
    cancel_requested BIGINT NOT NULL DEFAULT 0,
    progress         TEXT,
    summary          TEXT,
    message          TEXT,
    -- the sweep a job belongs to, its place in the sweep and its parameter values (0002)
    sweep_id         TEXT,
    sweep_index      BIGINT,
    sweep_label      TEXT,
    sweep_values     TEXT,
    -- the job a rerun was made from; not a foreign key (0004)
    rerun_of         TEXT,
    -- the canonical scene hash, and the completed job a cached copy serves (0006)
    scene_hash       TEXT,
    cached_from      TEXT,
    -- the job's own retry budget; NULL: the server's --max-attempts (0008)
    max_attempts     BIGINT
);
CREATE INDEX jobs_queue ON jobs (status, priority DESC, seq);
CREATE INDEX jobs_sweep ON jobs (sweep_id, sweep_index);
CREATE INDEX jobs_scene_hash ON jobs (scene_hash);

CREATE TABLE energy (
    rowid         BIGSERIAL PRIMARY KEY,
    job_id        TEXT NOT NULL,
    time          DOUBLE PRECISION,
    kinetic       DOUBLE PRECISION,
    strain        DOUBLE PRECISION,
    external_work DOUBLE PRECISION,
    dissipated    DOUBLE PRECISION,
    total_error   DOUBLE PRECISION,
    fracture      DOUBLE PRECISION
);
CREATE INDEX energy_job ON energy (job_id, time);

CREATE TABLE crack_tips (
    rowid     BIGSERIAL PRIMARY KEY,
    job_id    TEXT NOT NULL,
    time      DOUBLE PRECISION,
    crack     BIGINT NOT NULL,
    tip       BIGINT NOT NULL,
    x         DOUBLE PRECISION,
    y         DOUBLE PRECISION,
    length    DOUBLE PRECISION,
    speed     DOUBLE PRECISION,
    j1        DOUBLE PRECISION,
    j2        DOUBLE PRECISION,
    k1        DOUBLE PRECISION,
    k2        DOUBLE PRECISION,
    growing   BIGINT NOT NULL,
    -- the path-independence report and the crack-opening K (0003)
    j1_half   DOUBLE PRECISION,
    j2_half   DOUBLE PRECISION,
    j1_double DOUBLE PRECISION,
    j2_double DOUBLE PRECISION,
    k1_cod    DOUBLE PRECISION,
    k2_cod    DOUBLE PRECISION
);
CREATE INDEX crack_tips_job ON crack_tips (job_id, time);

CREATE TABLE snapshots (
    job_id TEXT NOT NULL,
    idx    BIGINT NOT NULL,
    time   DOUBLE PRECISION NOT NULL,
    fields TEXT NOT NULL,
    data   BYTEA NOT NULL,
    PRIMARY KEY (job_id, idx)
);

-- Parameter sweeps: a base scene and a grid of parameter values; one job per combination.
CREATE TABLE sweeps (
    seq            BIGSERIAL PRIMARY KEY,
    id             TEXT NOT NULL UNIQUE,
    name           TEXT NOT NULL,
    -- the base scene (JSON)
    scene          TEXT NOT NULL,
    -- [{"path", "values"}] in the order of the request
    parameters     TEXT NOT NULL,
    priority       BIGINT NOT NULL DEFAULT 0,
    labels         TEXT NOT NULL DEFAULT '{}',
    created_at     TEXT NOT NULL,
    -- most jobs of the sweep running at once; NULL: no limit (0007)
    max_concurrent BIGINT
);
