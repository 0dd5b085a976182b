// Loads a session report in headless Chromium (Debian's, through puppeteer-core) and checks what
// a clinician would see: every plot drawn, the repetition, warning and calibration tables, no
// script, no console error, no network request. Takes a full-page screenshot.
//   node check_report.js REPORT.html SCREENSHOT.png EXPECTED_WARNINGS
// EXPECTED_WARNINGS "any": a report of any session (the docs' picture): only the checks that
// hold for every report with angles, not the fixture's counts.
const path = require('path');
const puppeteer = require('puppeteer-core');

const [reportPath, screenshotPath, expectedWarnings] = process.argv.slice(2);
const expectedPlots = ['plot-thorax', 'plot-left-shoulder', 'plot-left-elbow', 'plot-right-shoulder', 'plot-right-elbow'];

(async () => {
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage'],
  });
  const problems = [];
  try {
    const page = await browser.newPage();
    page.on('console', (m) => { if (m.type() === 'error') problems.push(`console error: ${m.text()}`); });
    page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
    page.on('requestfailed', (r) => problems.push(`request failed: ${r.url()}`));
    page.on('request', (r) => { if (!r.url().startsWith('file:')) problems.push(`network request: ${r.url()}`); });
    await page.setViewport({ width: 1000, height: 900 });
    await page.goto('file://' + path.resolve(reportPath), { waitUntil: 'load' });
    const dom = await page.evaluate(() => ({
      plots: [...document.querySelectorAll('svg.plot')].map((svg) => ({
        id: svg.id,
        lines: svg.querySelectorAll('path.line').length,
        shades: svg.querySelectorAll('rect.shade').length,
        width: svg.getBoundingClientRect().width,
        height: svg.getBoundingClientRect().height,
      })),
      repetitionRows: document.querySelectorAll('table#repetitions tr').length,
      partialRows: document.querySelectorAll('table#repetitions tr.partial').length,
      uncertainRows: document.querySelectorAll('table#repetitions tr.counted.uncertain').length,
      summaryRows: document.querySelectorAll('table#repetition-summary tr').length,
      warnings: [...document.querySelectorAll('ul#warnings li')].map((li) => li.textContent),
      calibrationRows: document.querySelectorAll('table#calibration tr').length,
      scripts: document.scripts.length,
      bold: document.querySelectorAll('ul#warnings b').length,
    }));
    const ids = dom.plots.map((p) => p.id);
    if (JSON.stringify(ids) !== JSON.stringify(expectedPlots)) problems.push(`plots ${ids}, expected ${expectedPlots}`);
    for (const p of dom.plots) {
      if (p.lines < 1) problems.push(`${p.id}: no line drawn`);
      if (!(p.width > 500 && p.height > 100)) problems.push(`${p.id}: rendered ${p.width} x ${p.height} px`);
    }
    const fixture = expectedWarnings !== 'any';
    const rightShades = dom.plots.filter((p) => p.id.startsWith('plot-right')).map((p) => p.shades);
    if (fixture && !rightShades.every((n) => n >= 2)) problems.push(`right arm plots shade ${rightShades} stretches, expected the occlusion and its legend`);
    if (fixture && (dom.repetitionRows !== 4 || dom.partialRows !== 1)) problems.push(`repetition table: ${dom.repetitionRows} rows, ${dom.partialRows} partial`);
    if (fixture && dom.uncertainRows !== 1) problems.push(`repetition table: ${dom.uncertainRows} counted rows marked uncertain, expected 1`);
    if (fixture && dom.summaryRows !== 2) problems.push(`repetition summary: ${dom.summaryRows} rows`);
    if (fixture && dom.warnings.length !== Number(expectedWarnings)) problems.push(`${dom.warnings.length} warnings, expected ${expectedWarnings}`);
    if (fixture && !dom.warnings.some((w) => w.includes('<script>alert(1)</script> & <b>not bold</b>'))) problems.push('warning markup not shown as text');
    if (dom.scripts !== 0 || dom.bold !== 0) problems.push(`markup from a warning became elements (${dom.scripts} scripts, ${dom.bold} b)`);
    if (dom.calibrationRows < 3) problems.push(`calibration table: ${dom.calibrationRows} rows`);
    await page.screenshot({ path: screenshotPath, fullPage: true });
  } finally {
    await browser.close();
  }
  if (problems.length > 0) {
    for (const p of problems) console.error(`report browser test: FAILED: ${p}`);
    process.exit(1);
  }
  console.log(`report browser test: ${expectedPlots.length} plots, tables and warnings as expected; screenshot ${screenshotPath}`);
})().catch((e) => {
  console.error(`report browser test: FAILED: ${e.stack || e}`);
  process.exit(1);
});
