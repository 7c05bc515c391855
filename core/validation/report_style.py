"""The style sheet of the HTML reports (validation and curves): inline CSS, no fetch."""

CSS = """
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",sans-serif;margin:0 auto;max-width:1500px;
     padding:16px 24px;color:#1d1d1f;background:#fafafa}
h1{font-size:24px;margin:8px 0}h2{font-size:20px;margin:36px 0 8px;border-bottom:2px solid #ccc}
h3{font-size:16px;margin:20px 0 6px}
.meta{color:#555}.note{color:#666;font-size:12px}
table{border-collapse:collapse;margin:6px 0 14px;background:#fff;display:block;overflow-x:auto;width:max-content;max-width:100%}
th,td{border:1px solid #d0d0d0;padding:3px 8px;text-align:right;white-space:nowrap}
th{background:#eef0f3}td.l,th.l{text-align:left}
tr.gold td{background:#f3f3f3}tr.equal td{background:#f6f1fa}
.skip{color:#999}
td.win{font-weight:700;color:#0a6b2d}td.lose{color:#8a1c1c}
.grid{display:grid;gap:8px;align-items:start}
.maps{grid-template-columns:repeat(5,1fr)}
.pair{grid-template-columns:1fr 1fr}
.crops{grid-template-columns:repeat(5,1fr)}
figure{margin:0}figcaption{font-size:12px;color:#444;margin-top:2px}
img{width:100%;display:block;background:#000}
img.zoom{image-rendering:pixelated}
.framed{position:relative}
.box{position:absolute;border:2px solid #ffd400;box-shadow:0 0 0 1px #000}
.runs .name{font-weight:600;align-self:center}
svg.chart{max-width:100%;height:auto;font:12px system-ui,sans-serif;background:#fff}
"""
