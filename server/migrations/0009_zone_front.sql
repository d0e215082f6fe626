-- A cohesive interface's process-zone front (extra crack_tips.csv columns, at the end;
-- docs/run-output-extensions.md). NULL for rows written before: read back as NaN (null).
ALTER TABLE crack_tips ADD COLUMN zone_x REAL;
ALTER TABLE crack_tips ADD COLUMN zone_y REAL;
