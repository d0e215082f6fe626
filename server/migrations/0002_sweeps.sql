-- Parameter sweeps: a base scene and a grid of parameter values; one job per combination.
CREATE TABLE sweeps (
    seq        INTEGER PRIMARY KEY AUTOINCREMENT,
    id         TEXT NOT NULL UNIQUE,
    name       TEXT NOT NULL,
    -- the base scene (JSON)
    scene      TEXT NOT NULL,
    -- [{"path", "values"}] in the order of the request
    parameters TEXT NOT NULL,
    priority   INTEGER NOT NULL DEFAULT 0,
    labels     TEXT NOT NULL DEFAULT '{}',
    created_at TEXT NOT NULL
);

-- The sweep a job belongs to, its place in the sweep and its parameter values.
ALTER TABLE jobs ADD COLUMN sweep_id TEXT;
ALTER TABLE jobs ADD COLUMN sweep_index INTEGER;
ALTER TABLE jobs ADD COLUMN sweep_label TEXT;
ALTER TABLE jobs ADD COLUMN sweep_values TEXT;
CREATE INDEX jobs_sweep ON jobs (sweep_id, sweep_index);
