-- Jobs, their queue state, and what their runs produced.
CREATE TABLE jobs (
    seq              INTEGER PRIMARY KEY AUTOINCREMENT,
    id               TEXT NOT NULL UNIQUE,
    name             TEXT NOT NULL,
    status           TEXT NOT NULL,
    priority         INTEGER NOT NULL DEFAULT 0,
    labels           TEXT NOT NULL DEFAULT '{}',
    scene            TEXT NOT NULL,
    end_time         REAL NOT NULL,
    created_at       TEXT NOT NULL,
    started_at       TEXT,
    finished_at      TEXT,
    -- claims that count towards the attempt limit
    attempts         INTEGER NOT NULL DEFAULT 0,
    -- fencing token: +1 on every claim, never decreases
    fence            INTEGER NOT NULL DEFAULT 0,
    worker_id        TEXT,
    lease_until_ms   INTEGER,
    cancel_requested INTEGER NOT NULL DEFAULT 0,
    progress         TEXT,
    summary          TEXT,
    message          TEXT
);
CREATE INDEX jobs_queue ON jobs (status, priority DESC, seq);

CREATE TABLE energy (
    job_id        TEXT NOT NULL,
    time          REAL,
    kinetic       REAL,
    strain        REAL,
    external_work REAL,
    dissipated    REAL,
    total_error   REAL
);
CREATE INDEX energy_job ON energy (job_id, time);

CREATE TABLE crack_tips (
    job_id  TEXT NOT NULL,
    time    REAL,
    crack   INTEGER NOT NULL,
    tip     INTEGER NOT NULL,
    x       REAL,
    y       REAL,
    length  REAL,
    speed   REAL,
    j1      REAL,
    j2      REAL,
    k1      REAL,
    k2      REAL,
    growing INTEGER NOT NULL
);
CREATE INDEX crack_tips_job ON crack_tips (job_id, time);

CREATE TABLE snapshots (
    job_id TEXT NOT NULL,
    idx    INTEGER NOT NULL,
    time   REAL NOT NULL,
    fields TEXT NOT NULL,
    data   BLOB NOT NULL,
    PRIMARY KEY (job_id, idx)
);
