// ESLint for the npm module (src/, its tests, its build script) and for the page and widget built on
// it (axialdeform/web/*.js).  Run from the repository root: `npm run lint --prefix js` (with tsc);
// tests/web/test_three.py runs both.
import js from '@eslint/js';
import globals from 'globals';

const rules = { 'no-unused-vars': ['error', { argsIgnorePattern: '^_', caughtErrors: 'none' }] };

export default [
  // generated (js/src/webgl/glsl.js from glsl/ by build.mjs) or vendored
  { ignores: ['**/node_modules/**', 'js/src/webgl/glsl.js', 'axialdeform/web/vendor/**'] },
  { files: ['js/**/*.js', 'js/**/*.mjs', 'axialdeform/web/*.js'], ...js.configs.recommended },
  {
    files: ['js/**/*.js', 'js/**/*.mjs'],
    languageOptions: { ecmaVersion: 2022, sourceType: 'module', globals: { ...globals.browser, ...globals.node } },
    rules,
  },
  {
    files: ['axialdeform/web/*.js'],
    languageOptions: { ecmaVersion: 2022, sourceType: 'module', globals: { ...globals.browser } },
    rules,
  },
];
